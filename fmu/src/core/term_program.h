/* The regressor of a model file as data: the equations of motion
 *     sum_k theta_k Y_ik(q, q', q'', u) = r_i(q, q', q'', u),   i = 1..n,
 * linear in the unknown parameters theta, with every entry Y_ik and r_i an
 * expression of the coordinates q, their velocities q' and accelerations q''
 * and the known inputs u, compiled by the harness (harness/model/program.py)
 * into a postfix program over a constant pool.  The core evaluates the
 * program at every sample, so one FMU binary serves every model file: the
 * model reaches it as a resource file, never as generated C.
 *
 * Y's columns are in the file's units of the parameters (Y theta = r with
 * theta as the file writes it, r in SI).
 *
 * The text form (one token per word, '#' starts a comment line):
 *     sto-term-program 1
 *     sizes N M P           coordinates, inputs, parameters
 *     constants C  c_1 .. c_C
 *     nominal v_1 .. v_P    the parameters' nominal values (the file's units)
 *     scale s_1 .. s_P      each parameter's unit in SI (theta_SI = s theta)
 *     coordinate_scale c_1 .. c_N   optional: each coordinate's unit in SI (default 1)
 *     bounds l_1 u_1 .. l_P u_P     optional: each parameter's declared range (the
 *                           file's units; -inf, inf for an open end), the nominal inside
 *     names n_1 .. n_P      optional: the parameters' names, for messages (letters,
 *                           digits and _, at most TP_NAME_SIZE - 1; default theta_k)
 *     identifier K          optional: the identifier the model asks for (1 LSM, the
 *                           default; 2 MFF for time-varying parameters; 0 none)
 *     inputs_held H         optional: 1 when each input sample acts until the next (a
 *                           zero-order hold: the model file's [log] inputs = "held")
 *     entry I K L  op arg .. op arg     L (op, arg) pairs; K = P: r_I
 * with one entry for every I < N and K <= P.  Ops (term_program.c, TpOp)
 * push a constant (arg: its index) or a measured value (arg: the coordinate
 * or input index), or apply + * ^ to the top two values or a function to the
 * top one (arg 0).  tp_parse checks everything: sizes within the limits
 * below, indices in range, every entry leaving exactly one value on a stack
 * of at most TP_MAX_STACK, so that tp_evaluate needs no check.
 * Plain C, no allocation, no I/O. */
#ifndef TERM_PROGRAM_H
#define TERM_PROGRAM_H

#include <stddef.h>

#define TP_MAX_COORDINATES 7
#define TP_MAX_INPUTS 7
#define TP_MAX_PARAMETERS 32
#define TP_NAME_SIZE 32
#define TP_MAX_TOKENS 4096
#define TP_MAX_CONSTANTS 512
#define TP_MAX_STACK 32
#define TP_MAX_TEXT 1000000 /* bytes of the text form */

typedef enum {
    TP_CONSTANT, TP_POSITION, TP_VELOCITY, TP_ACCELERATION, TP_INPUT,
    TP_ADD, TP_MULTIPLY, TP_POWER,
    TP_NEGATE, TP_SIN, TP_COS, TP_TAN, TP_TANH, TP_EXP, TP_LOG, TP_SIGN, TP_ABS, TP_SQRT,
    TP_ATAN, TP_SINH, TP_COSH,
    TP_OP_COUNT
} TpOp;

typedef struct {
    int n, m, p;                   /* coordinates, inputs, parameters */
    int n_constants, n_tokens;
    double constant[TP_MAX_CONSTANTS];
    double nominal[TP_MAX_PARAMETERS], scale[TP_MAX_PARAMETERS];
    /* the ranges the model file declares, in its units (-inf, inf: none) */
    double lower[TP_MAX_PARAMETERS], upper[TP_MAX_PARAMETERS];
    int bounded;                   /* some parameter has a range */
    double coordinate_scale[TP_MAX_COORDINATES];
    char names[TP_MAX_PARAMETERS][TP_NAME_SIZE]; /* of the parameters, for messages */
    int identifier;
    int inputs_held;               /* each input sample acts until the next */
    int op[TP_MAX_TOKENS], arg[TP_MAX_TOKENS];
    /* entry (i, k), k <= p (k = p: r_i): tokens start[i][k] .. start[i][k] + length[i][k] - 1 */
    int start[TP_MAX_COORDINATES][TP_MAX_PARAMETERS + 1];
    int length[TP_MAX_COORDINATES][TP_MAX_PARAMETERS + 1];
} TermProgram;

/* One sample's values, in SI units as the program expects them. */
typedef struct {
    double q[TP_MAX_COORDINATES], qd[TP_MAX_COORDINATES], qdd[TP_MAX_COORDINATES];
    double u[TP_MAX_INPUTS];
} TpSample;

/* Reads the text form (`length` bytes, no terminator needed).  Returns 0, or
 * -1 with a message naming the problem (line and token) in error[error_size]. */
int tp_parse(TermProgram *program, const char *text, size_t length, char *error,
             size_t error_size);

/* Y (n x p, row-major in rows of TP_MAX_PARAMETERS) and r (n) at one sample. */
void tp_evaluate(const TermProgram *program, const TpSample *sample,
                 double Y[][TP_MAX_PARAMETERS], double r[]);

/* Entry (i, k) alone (k = p: r_i). */
double tp_entry(const TermProgram *program, const TpSample *sample, int i, int k);

/* What entry (i, k) reads, and whether it is nonlinear: not a constant plus constant
 * multiples of what it reads (a function of a position, a product of two, a power). */
enum { TP_READS_POSITIONS = 1, TP_READS_INPUTS = 2, TP_READS_DERIVATIVES = 4, TP_NONLINEAR = 8 };
int tp_entry_kind(const TermProgram *program, int i, int k);

/* The coordinates whose velocity equation i reads inside sign() (Coulomb friction), as
 * bits 1 << j: the equation holds as written only where they move. */
int tp_sign_velocities(const TermProgram *program, int i);

#endif
