#include "term_program.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- reading the text form ---- */

#define TOKEN_SIZE 64

typedef struct {
    const char *text;
    size_t length, at;
    int line;
    char token[TOKEN_SIZE];
    char *error;
    size_t error_size;
} Cursor;

static int fail(Cursor *c, const char *format, ...)
{
    if (c->error && c->error_size) {
        int used = snprintf(c->error, c->error_size, "term program, line %d: ", c->line);
        if (used < 0) used = 0;
        if ((size_t)used < c->error_size) {
            va_list args;
            va_start(args, format);
            vsnprintf(c->error + used, c->error_size - (size_t)used, format, args);
            va_end(args);
        }
    }
    return -1;
}

static int is_space(char ch) { return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\n'; }

/* The next word into c->token; 0, or -1 at the end of the text or for a word
 * too long to be a number or keyword. */
static int next_word(Cursor *c)
{
    for (;;) {
        while (c->at < c->length && is_space(c->text[c->at])) {
            if (c->text[c->at] == '\n') ++c->line;
            ++c->at;
        }
        if (c->at < c->length && c->text[c->at] == '#') {
            while (c->at < c->length && c->text[c->at] != '\n') ++c->at;
            continue;
        }
        break;
    }
    if (c->at >= c->length) return fail(c, "the text ends where a word was expected");
    size_t size = 0;
    while (c->at < c->length && !is_space(c->text[c->at]) && c->text[c->at] != '#') {
        if (c->text[c->at] == '\0') return fail(c, "a NUL byte in the text");
        if (size + 1 >= TOKEN_SIZE) return fail(c, "a word longer than %d characters",
                                                TOKEN_SIZE - 1);
        c->token[size++] = c->text[c->at++];
    }
    c->token[size] = '\0';
    return 0;
}

static int expect_word(Cursor *c, const char *word)
{
    if (next_word(c)) return -1;
    if (strcmp(c->token, word) != 0)
        return fail(c, "expected '%s', found '%s'", word, c->token);
    return 0;
}

/* A parameter's name: a letter, then letters, digits or _, shorter than TP_NAME_SIZE
 * (it goes into messages as it is). */
static int read_name(Cursor *c, char name[TP_NAME_SIZE])
{
    if (next_word(c)) return -1;
    const size_t size = strlen(c->token);
    int valid = size < TP_NAME_SIZE && isalpha((unsigned char)c->token[0]);
    for (size_t j = 0; valid && j < size; ++j)
        valid = isalnum((unsigned char)c->token[j]) || c->token[j] == '_';
    if (!valid)
        return fail(c, "parameter name '%s' is not a name of at most %d letters, digits or _",
                    c->token, TP_NAME_SIZE - 1);
    memcpy(name, c->token, size + 1);
    return 0;
}

static int read_int(Cursor *c, const char *what, long lo, long hi, int *value)
{
    if (next_word(c)) return -1;
    char *end = NULL;
    errno = 0;
    const long v = strtol(c->token, &end, 10);
    if (end == c->token || *end != '\0' || errno)
        return fail(c, "%s: '%s' is not an integer", what, c->token);
    if (v < lo || v > hi) return fail(c, "%s = %ld is outside [%ld, %ld]", what, v, lo, hi);
    *value = (int)v;
    return 0;
}

static int read_double(Cursor *c, const char *what, double *value)
{
    if (next_word(c)) return -1;
    char *end = NULL;
    const double v = strtod(c->token, &end);
    if (end == c->token || *end != '\0') return fail(c, "%s: '%s' is not a number", what, c->token);
    if (!isfinite(v)) return fail(c, "%s = %s is not finite", what, c->token);
    *value = v;
    return 0;
}

/* An end of a range: a finite number, or "-inf" (lower) / "inf" (upper) for none. */
static int read_end(Cursor *c, const char *what, int upper, double *value)
{
    if (next_word(c)) return -1;
    if (strcmp(c->token, upper ? "inf" : "-inf") == 0) {
        *value = upper ? INFINITY : -INFINITY;
        return 0;
    }
    char *end = NULL;
    const double v = strtod(c->token, &end);
    if (end == c->token || *end != '\0' || !isfinite(v))
        return fail(c, "%s: '%s' is not a finite number or %s", what, c->token,
                    upper ? "inf" : "-inf");
    *value = v;
    return 0;
}

/* "bounds" then lower upper per parameter: lower < upper, the nominal inside. */
static int read_bounds(Cursor *c, TermProgram *p)
{
    for (int k = 0; k < p->p; ++k) {
        if (read_end(c, "lower bound", 0, &p->lower[k]) ||
            read_end(c, "upper bound", 1, &p->upper[k]))
            return -1;
        if (!(p->lower[k] < p->upper[k]))
            return fail(c, "range of parameter %d = [%g, %g] is empty", k, p->lower[k],
                        p->upper[k]);
        if (!(p->lower[k] <= p->nominal[k] && p->nominal[k] <= p->upper[k]))
            return fail(c, "nominal value of parameter %d = %g is outside its range [%g, %g]",
                        k, p->nominal[k], p->lower[k], p->upper[k]);
    }
    p->bounded = 1;
    return 0;
}

/* How many values an op takes from the stack and the range of its argument. */
static int op_arity(int op) { return op <= TP_INPUT ? 0 : op <= TP_POWER ? 2 : 1; }

static int arg_limit(const TermProgram *p, int op)
{
    switch (op) {
    case TP_CONSTANT: return p->n_constants;
    case TP_POSITION: case TP_VELOCITY: case TP_ACCELERATION: return p->n;
    case TP_INPUT: return p->m;
    default: return 1; /* arg 0 */
    }
}

static int read_entry(Cursor *c, TermProgram *p)
{
    int i, k, length;
    if (read_int(c, "entry row", 0, p->n - 1, &i) || read_int(c, "entry column", 0, p->p, &k) ||
        read_int(c, "entry length", 1, TP_MAX_TOKENS, &length))
        return -1;
    if (p->length[i][k]) return fail(c, "entry %d %d is given twice", i, k);
    if (length > TP_MAX_TOKENS - p->n_tokens)
        return fail(c, "more than %d tokens in all", TP_MAX_TOKENS);
    int depth = 0;
    p->start[i][k] = p->n_tokens;
    for (int t = 0; t < length; ++t) {
        int op, arg;
        if (read_int(c, "op", 0, TP_OP_COUNT - 1, &op) || read_int(c, "arg", 0, 1 << 20, &arg))
            return -1;
        if (arg >= arg_limit(p, op))
            return fail(c, "entry %d %d, token %d: argument %d out of range for op %d", i, k, t,
                        arg, op);
        const int arity = op_arity(op);
        if (depth < arity)
            return fail(c, "entry %d %d, token %d: op %d needs %d values, the stack holds %d", i,
                        k, t, op, arity, depth);
        depth += 1 - arity;
        if (depth > TP_MAX_STACK)
            return fail(c, "entry %d %d: deeper than %d values", i, k, TP_MAX_STACK);
        p->op[p->n_tokens] = op;
        p->arg[p->n_tokens] = arg;
        ++p->n_tokens;
    }
    if (depth != 1) return fail(c, "entry %d %d leaves %d values, not 1", i, k, depth);
    p->length[i][k] = length;
    return 0;
}

int tp_parse(TermProgram *p, const char *text, size_t length, char *error, size_t error_size)
{
    Cursor c = {.text = text, .length = length, .line = 1, .error = error,
                .error_size = error_size};
    memset(p, 0, sizeof *p);
    if (!text) return fail(&c, "no text");
    if (length > TP_MAX_TEXT) return fail(&c, "longer than %d bytes", TP_MAX_TEXT);
    int version;
    if (expect_word(&c, "sto-term-program") || read_int(&c, "version", 1, 1, &version) ||
        expect_word(&c, "sizes") ||
        read_int(&c, "coordinates", 1, TP_MAX_COORDINATES, &p->n) ||
        read_int(&c, "inputs", 0, TP_MAX_INPUTS, &p->m) ||
        read_int(&c, "parameters", 1, TP_MAX_PARAMETERS, &p->p) ||
        expect_word(&c, "constants") ||
        read_int(&c, "constants", 0, TP_MAX_CONSTANTS, &p->n_constants))
        return -1;
    for (int j = 0; j < p->n_constants; ++j)
        if (read_double(&c, "constant", &p->constant[j])) return -1;
    if (expect_word(&c, "nominal")) return -1;
    for (int k = 0; k < p->p; ++k)
        if (read_double(&c, "nominal", &p->nominal[k])) return -1;
    if (expect_word(&c, "scale")) return -1;
    for (int k = 0; k < p->p; ++k) {
        if (read_double(&c, "scale", &p->scale[k])) return -1;
        if (!(p->scale[k] > 0.0)) return fail(&c, "scale of parameter %d = %g is not positive",
                                              k, p->scale[k]);
    }
    p->identifier = 1;
    for (int i = 0; i < p->n; ++i) p->coordinate_scale[i] = 1.0;
    for (int k = 0; k < p->p; ++k) {
        p->lower[k] = -INFINITY;
        p->upper[k] = INFINITY;
    }
    if (next_word(&c)) return -1;
    if (strcmp(c.token, "coordinate_scale") == 0) {
        for (int i = 0; i < p->n; ++i) {
            if (read_double(&c, "coordinate_scale", &p->coordinate_scale[i])) return -1;
            if (!(p->coordinate_scale[i] > 0.0))
                return fail(&c, "coordinate_scale of coordinate %d = %g is not positive", i,
                            p->coordinate_scale[i]);
        }
        if (next_word(&c)) return -1;
    }
    if (strcmp(c.token, "bounds") == 0) {
        if (read_bounds(&c, p) || next_word(&c)) return -1;
    }
    for (int k = 0; k < p->p; ++k) snprintf(p->names[k], TP_NAME_SIZE, "theta_%d", k + 1);
    if (strcmp(c.token, "names") == 0) {
        for (int k = 0; k < p->p; ++k)
            if (read_name(&c, p->names[k])) return -1;
        if (next_word(&c)) return -1;
    }
    if (strcmp(c.token, "identifier") == 0) {
        if (read_int(&c, "identifier", 0, 2, &p->identifier) || next_word(&c)) return -1;
    }
    p->inputs_held = 0;
    if (strcmp(c.token, "inputs_held") == 0) {
        if (read_int(&c, "inputs_held", 0, 1, &p->inputs_held) || next_word(&c)) return -1;
    }
    const int entries = p->n * (p->p + 1);
    for (int e = 0; e < entries; ++e) {
        if (e > 0 && next_word(&c)) return -1;
        if (strcmp(c.token, "entry") != 0) return fail(&c, "expected 'entry', found '%s'", c.token);
        if (read_entry(&c, p)) return -1;
    }
    if (next_word(&c) == 0) return fail(&c, "'%s' after the last entry", c.token);
    if (error && error_size) error[0] = '\0';
    return 0;
}

/* ---- evaluation ---- */

static double sign(double x) { return (double)((x > 0.0) - (x < 0.0)); }

double tp_entry(const TermProgram *p, const TpSample *s, int i, int k)
{
    double stack[TP_MAX_STACK];
    int top = -1; /* tp_parse proved every entry's depth */
    const int end = p->start[i][k] + p->length[i][k];
    for (int t = p->start[i][k]; t < end; ++t) {
        const int a = p->arg[t];
        switch ((TpOp)p->op[t]) {
        case TP_CONSTANT: stack[++top] = p->constant[a]; break;
        case TP_POSITION: stack[++top] = s->q[a]; break;
        case TP_VELOCITY: stack[++top] = s->qd[a]; break;
        case TP_ACCELERATION: stack[++top] = s->qdd[a]; break;
        case TP_INPUT: stack[++top] = s->u[a]; break;
        case TP_ADD: --top; stack[top] += stack[top + 1]; break;
        case TP_MULTIPLY: --top; stack[top] *= stack[top + 1]; break;
        case TP_POWER: --top; stack[top] = pow(stack[top], stack[top + 1]); break;
        case TP_NEGATE: stack[top] = -stack[top]; break;
        case TP_SIN: stack[top] = sin(stack[top]); break;
        case TP_COS: stack[top] = cos(stack[top]); break;
        case TP_TAN: stack[top] = tan(stack[top]); break;
        case TP_TANH: stack[top] = tanh(stack[top]); break;
        case TP_EXP: stack[top] = exp(stack[top]); break;
        case TP_LOG: stack[top] = log(stack[top]); break;
        case TP_SIGN: stack[top] = sign(stack[top]); break;
        case TP_ABS: stack[top] = fabs(stack[top]); break;
        case TP_SQRT: stack[top] = sqrt(stack[top]); break;
        case TP_ATAN: stack[top] = atan(stack[top]); break;
        case TP_SINH: stack[top] = sinh(stack[top]); break;
        case TP_COSH: stack[top] = cosh(stack[top]); break;
        case TP_OP_COUNT: break;
        }
    }
    return stack[0];
}

void tp_evaluate(const TermProgram *p, const TpSample *s, double Y[][TP_MAX_PARAMETERS],
                 double r[])
{
    for (int i = 0; i < p->n; ++i) {
        for (int k = 0; k < p->p; ++k) Y[i][k] = tp_entry(p, s, i, k);
        r[i] = tp_entry(p, s, i, p->p);
    }
}

int tp_entry_kind(const TermProgram *p, int i, int k)
{
    enum { CONSTANT, AFFINE, NONLINEAR }; /* each stack value's form */
    int stack[TP_MAX_STACK], top = -1, reads = 0;
    const int start = p->start[i][k], end = start + p->length[i][k];
    for (int t = start; t < end; ++t) {
        switch ((TpOp)p->op[t]) {
        case TP_CONSTANT: stack[++top] = CONSTANT; break;
        case TP_POSITION: stack[++top] = AFFINE; reads |= TP_READS_POSITIONS; break;
        case TP_VELOCITY: case TP_ACCELERATION:
            stack[++top] = AFFINE;
            reads |= TP_READS_DERIVATIVES;
            break;
        case TP_INPUT: stack[++top] = AFFINE; reads |= TP_READS_INPUTS; break;
        case TP_ADD:
            --top;
            stack[top] = stack[top] > stack[top + 1] ? stack[top] : stack[top + 1];
            break;
        case TP_MULTIPLY:
            --top;
            stack[top] = stack[top] == CONSTANT ? stack[top + 1]
                         : stack[top + 1] == CONSTANT ? stack[top] : NONLINEAR;
            break;
        case TP_POWER:
            --top;
            stack[top] = stack[top] == CONSTANT && stack[top + 1] == CONSTANT ? CONSTANT
                                                                              : NONLINEAR;
            break;
        case TP_NEGATE: break;
        case TP_OP_COUNT: break;
        default: stack[top] = stack[top] == CONSTANT ? CONSTANT : NONLINEAR; break;
        }
    }
    return reads | (top == 0 && stack[0] == NONLINEAR ? TP_NONLINEAR : 0);
}

int tp_sign_velocities(const TermProgram *p, int i)
{
    int inside = 0;
    for (int k = 0; k <= p->p; ++k) {
        int stack[TP_MAX_STACK], top = -1; /* the velocities each stack value reads */
        const int start = p->start[i][k], end = start + p->length[i][k];
        for (int t = start; t < end; ++t) {
            switch ((TpOp)p->op[t]) {
            case TP_CONSTANT: case TP_POSITION: case TP_ACCELERATION: case TP_INPUT:
                stack[++top] = 0;
                break;
            case TP_VELOCITY: stack[++top] = 1 << p->arg[t]; break;
            case TP_ADD: case TP_MULTIPLY: case TP_POWER:
                --top;
                stack[top] |= stack[top + 1];
                break;
            case TP_SIGN: inside |= stack[top]; break;
            default: break; /* functions of one value read what it reads */
            }
        }
    }
    return inside;
}
