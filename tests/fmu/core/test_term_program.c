/* Unit tests of the term program (fmu/src/core/term_program.h), the model
 * file's regressor as data: run as `test_term_program CASE` (check.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"

#include "term_program.h"

/* The EMPS drive, M q'' + Fv q' + Fc sign(q') + OF = F with q in mm (factor
 * 1e-3 to SI folded into the program): Y = [1e-3 q'', 1e-3 q', sign(q'), 1],
 * r = F. */
static const char EMPS[] =
    "sto-term-program 1\n"
    "# a comment line\n"
    "sizes 1 1 4\n"
    "constants 2 0.001 1\n"
    "nominal 100 0 0 0\n"
    "scale 1 1 1 1\n"
    "coordinate_scale 0.001\n"
    "entry 0 0 3  0 0  3 0  6 0\n"
    "entry 0 1 3  0 0  2 0  6 0\n"
    "entry 0 2 2  2 0  15 0\n"
    "entry 0 3 1  0 1\n"
    "entry 0 4 1  4 0\n";

static int evaluates_a_drive(void)
{
    static TermProgram program;
    char error[256];
    int failed = check(tp_parse(&program, EMPS, strlen(EMPS), error, sizeof error) == 0,
                       "the EMPS program parses ('%s')", error);
    TpSample s = {.q = {12.0}, .qd = {-250.0}, .qdd = {3000.0}, .u = {42.5}};
    double Y[TP_MAX_COORDINATES][TP_MAX_PARAMETERS], r[TP_MAX_COORDINATES];
    tp_evaluate(&program, &s, Y, r);
    failed += check(Y[0][0] == 3.0 && Y[0][1] == -0.25 && Y[0][2] == -1.0 && Y[0][3] == 1.0,
                    "Y = [%g, %g, %g, %g], expected [3, -0.25, -1, 1]", Y[0][0], Y[0][1], Y[0][2],
                    Y[0][3]);
    failed += check(r[0] == 42.5, "r = %g, expected 42.5", r[0]);
    failed += check(program.identifier == 1, "identifier %d: LSM by default", program.identifier);
    failed += check(program.coordinate_scale[0] == 0.001, "coordinate scale %g (mm)",
                    program.coordinate_scale[0]);
    return failed;
}

/* The velocities inside sign(): the drive's q' (bit 0); two coordinates where
 * equation 0 reads sign(q1' * q0) + q0' (bit 1 only: q0' is outside the sign) and
 * equation 1 sign(q0') (bit 0). */
static int finds_the_velocities_inside_sign(void)
{
    static TermProgram program;
    char error[256];
    int failed = check(tp_parse(&program, EMPS, strlen(EMPS), error, sizeof error) == 0,
                       "the EMPS program parses ('%s')", error);
    failed += check(tp_sign_velocities(&program, 0) == 1, "the drive: %d, expected 1",
                    tp_sign_velocities(&program, 0));
    static const char TWO[] = "sto-term-program 1 sizes 2 0 1 constants 0 nominal 0 scale 1\n"
                              "entry 0 0 6  2 1  1 0  6 0  15 0  2 0  5 0\n"
                              "entry 0 1 1  2 0\n"
                              "entry 1 0 2  2 0  15 0\n"
                              "entry 1 1 1  1 1\n";
    failed += check(tp_parse(&program, TWO, strlen(TWO), error, sizeof error) == 0,
                    "the two-coordinate program parses ('%s')", error);
    failed += check(tp_sign_velocities(&program, 0) == 2 && tp_sign_velocities(&program, 1) == 1,
                    "equations 0 and 1: %d and %d, expected 2 and 1",
                    tp_sign_velocities(&program, 0), tp_sign_velocities(&program, 1));
    return failed;
}

/* Every op against the C library: one entry per op applied to q = 0.3 (and
 * for the binary ops q and q'' = 1.7). */
static int every_op(void)
{
    static const struct {
        int op;
        double expected;
    } unary[] = {
        {TP_NEGATE, -0.3}, {TP_SIN, 0.29552020666133955}, {TP_COS, 0.955336489125606},
        {TP_TAN, 0.30933624960962325}, {TP_TANH, 0.2913126124515909},
        {TP_EXP, 1.3498588075760032}, {TP_LOG, -1.2039728043259361}, {TP_SIGN, 1.0},
        {TP_ABS, 0.3}, {TP_SQRT, 0.5477225575051661}, {TP_ATAN, 0.2914567944778671},
        {TP_SINH, 0.3045202934471426}, {TP_COSH, 1.0453385141288605},
    };
    const size_t n_unary = sizeof unary / sizeof unary[0];
    char text[4096];
    int used = snprintf(text, sizeof text, "sto-term-program 1 sizes 1 0 %d constants 0\n",
                        (int)n_unary + 3);
    used += snprintf(text + used, sizeof text - (size_t)used, "nominal");
    for (size_t k = 0; k < n_unary + 3; ++k)
        used += snprintf(text + used, sizeof text - (size_t)used, " 0");
    used += snprintf(text + used, sizeof text - (size_t)used, " scale");
    for (size_t k = 0; k < n_unary + 3; ++k)
        used += snprintf(text + used, sizeof text - (size_t)used, " 1");
    used += snprintf(text + used, sizeof text - (size_t)used, "\n");
    for (size_t k = 0; k < n_unary; ++k)
        used += snprintf(text + used, sizeof text - (size_t)used, "entry 0 %d 2 1 0 %d 0\n",
                         (int)k, unary[k].op);
    for (int b = 0; b < 3; ++b)
        used += snprintf(text + used, sizeof text - (size_t)used, "entry 0 %d 3 1 0 3 0 %d 0\n",
                         (int)n_unary + b, TP_ADD + b);
    used += snprintf(text + used, sizeof text - (size_t)used, "entry 0 %d 1 3 0\n",
                     (int)n_unary + 3);
    static TermProgram program;
    char error[256];
    int failed = check(tp_parse(&program, text, (size_t)used, error, sizeof error) == 0,
                       "a program of every op parses ('%s')", error);
    const TpSample s = {.q = {0.3}, .qdd = {1.7}};
    for (size_t k = 0; k < n_unary; ++k) {
        const double v = tp_entry(&program, &s, 0, (int)k);
        failed += check(fabs(v - unary[k].expected) <= 1e-15, "op %d of 0.3 = %.17g, expected %.17g",
                        unary[k].op, v, unary[k].expected);
    }
    const double binary[3] = {2.0, 0.3 * 1.7, pow(0.3, 1.7)};
    for (int b = 0; b < 3; ++b) {
        const double v = tp_entry(&program, &s, 0, (int)n_unary + b);
        failed += check(fabs(v - binary[b]) <= 1e-15, "op %d of (0.3, 1.7) = %.17g, expected %.17g",
                        TP_ADD + b, v, binary[b]);
    }
    return failed;
}

/* Each malformed text is refused with a message naming its problem. */
static int refuses_bad_programs(void)
{
    static const struct {
        const char *text, *message;
    } bad[] = {
        {"", "the text ends"},
        {"sto-term-program 2", "version = 2"},
        {"sto-term-program 1 sizes 8 0 1", "coordinates = 8"},
        {"sto-term-program 1 sizes 1 0 33", "parameters = 33"},
        {"sto-term-program 1 sizes 1 0 1 constants 1 nan", "not finite"},
        {"sto-term-program 1 sizes 1 0 1 constants 1 1e999", "not finite"},
        {"sto-term-program 1 sizes 1 0 1 constants 1 x", "'x' is not a number"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 1 scale 0", "not positive"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 1 scale -1", "not positive"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal inf", "not finite"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 entry", "expected 'nominal'"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 identifier 3",
         "identifier = 3"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 coordinate_scale 0",
         "coordinate_scale of coordinate 0 = 0 is not positive"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 identifier 2 x",
         "expected 'entry', found 'x'"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 0 0", "argument 0 out of range"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 4 0", "argument 0 out of range"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 5 0", "needs 2 values"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 2 1 0 1 0", "leaves 2 values"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 99 0", "op = 99"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 1 0 entry 0 0 1 1 0",
         "given twice"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 1 0 entry 0 1 1 1 0 extra",
         "'extra' after the last entry"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 1 0", "the text ends"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 1 0 1 1 0", "entry row = 1"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 1 -1", "arg = -1"},
        {"sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 1 1 "
         "12345678901234567890123456789012345678901234567890123456789012345678",
         "longer than 63"},
    };
    static TermProgram program;
    int failed = 0;
    for (size_t j = 0; j < sizeof bad / sizeof bad[0]; ++j) {
        char error[256] = "";
        const int status = tp_parse(&program, bad[j].text, strlen(bad[j].text), error, sizeof error);
        failed += check(status == -1 && strstr(error, bad[j].message) != NULL,
                        "'%.40s...' refused (%d) naming '%s': %s", bad[j].text, status,
                        bad[j].message, error);
    }
    /* A stack deeper than TP_MAX_STACK: TP_MAX_STACK + 1 pushes. */
    char deep[2048];
    int used = snprintf(deep, sizeof deep, "sto-term-program 1 sizes 1 0 1 constants 0 nominal 0 scale 1 entry 0 0 %d",
                        2 * TP_MAX_STACK + 1);
    for (int t = 0; t <= TP_MAX_STACK; ++t) used += snprintf(deep + used, sizeof deep - (size_t)used, " 1 0");
    for (int t = 0; t < TP_MAX_STACK; ++t) used += snprintf(deep + used, sizeof deep - (size_t)used, " 5 0");
    char error[256] = "";
    failed += check(tp_parse(&program, deep, (size_t)used, error, sizeof error) == -1 &&
                    strstr(error, "deeper than") != NULL, "a stack of %d refused: %s",
                    TP_MAX_STACK + 1, error);
    /* A NUL byte inside the length given. */
    static const char with_nul[] = "sto-term-program 1\0 sizes";
    failed += check(tp_parse(&program, with_nul, sizeof with_nul - 1, error, sizeof error) == -1 &&
                    strstr(error, "NUL") != NULL, "a NUL byte refused: %s", error);
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"evaluates_a_drive", evaluates_a_drive},
        {"every_op", every_op},
        {"finds_the_velocities_inside_sign", finds_the_velocities_inside_sign},
        {"refuses_bad_programs", refuses_bad_programs},
    };
    return run_cases("test_term_program", cases, sizeof cases / sizeof cases[0], argc, argv);
}
