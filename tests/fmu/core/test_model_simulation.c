/* Unit tests of a model file's equations simulated (fmu/src/core/model_simulation.h):
 * run as `test_model_simulation CASE` (check.h). */
#include <math.h>
#include <string.h>

#include "check.h"

#include "model_simulation.h"

/* m q'' + d q' + k q = u: Y = [q'', q', q], r = u. */
static const char OSCILLATOR[] =
    "sto-term-program 1\n"
    "sizes 1 1 3\n"
    "constants 0\n"
    "nominal 1 0 1\n"
    "scale 1 1 1\n"
    "entry 0 0 1  3 0\n"
    "entry 0 1 1  2 0\n"
    "entry 0 2 1  1 0\n"
    "entry 0 3 1  4 0\n";

/* m1 q1'' + k (q1 - q2) = u;  m2 q2'' + m2/2 q1'' + k (q2 - q1) = 0: theta = [m1, m2, k]. */
static const char TWO_MASSES[] =
    "sto-term-program 1\n"
    "sizes 2 1 3\n"
    "constants 2 0 0.5\n"
    "nominal 2 1 50\n"
    "scale 1 1 1\n"
    "entry 0 0 1  3 0\n"
    "entry 0 1 1  0 0\n"
    "entry 0 2 4  1 0  1 1  8 0  5 0\n"
    "entry 0 3 1  4 0\n"
    "entry 1 0 1  0 0\n"
    "entry 1 1 5  3 1  0 1  3 0  6 0  5 0\n"
    "entry 1 2 4  1 1  1 0  8 0  5 0\n"
    "entry 1 3 1  0 0\n";

/* m q'' = u - q''/2: a known inertia on the right side (r reads q''): theta = [m]. */
static const char KNOWN_INERTIA[] =
    "sto-term-program 1\n"
    "sizes 1 1 1\n"
    "constants 1 0.5\n"
    "nominal 1\n"
    "scale 1\n"
    "entry 0 0 1  3 0\n"
    "entry 0 1 6  4 0  0 0  3 0  6 0  8 0  5 0\n";

static int parse(TermProgram *program, const char *text)
{
    char error[256] = "";
    return check(tp_parse(program, text, strlen(text), error, sizeof error) == 0,
                 "the program parses ('%s')", error);
}

static int solves_the_mass_matrix(void)
{
    static TermProgram program;
    int failed = parse(&program, TWO_MASSES);
    const double theta[] = {2.0, 1.0, 50.0}, q[] = {0.1, -0.05}, qd[] = {0.0, 0.0}, u[] = {1.0};
    double qdd[2];
    const int status = ms_accelerations(&program, theta, q, qd, u, qdd);
    /* 2 a1 + 7.5 = 1; a2 + a1 / 2 - 7.5 = 0 */
    failed += check(status == 0 && fabs(qdd[0] + 3.25) < 1e-12 && fabs(qdd[1] - 9.125) < 1e-12,
                    "q'' = (%.15g, %.15g), expected (-3.25, 9.125)", qdd[0], qdd[1]);
    const double massless[] = {0.0, 1.0, 50.0};
    failed += check(ms_accelerations(&program, massless, q, qd, u, qdd) == -1 && isnan(qdd[0]),
                    "a singular mass matrix gives -1 and NaN");
    static TermProgram known;
    failed += parse(&known, KNOWN_INERTIA);
    const double m[] = {1.5}, force[] = {2.0};
    failed += check(ms_accelerations(&known, m, q, qd, force, qdd) == 0 &&
                    fabs(qdd[0] - 1.0) < 1e-15, "the right side's inertia: q'' = %.17g, "
                    "expected 1", qdd[0]);
    return failed;
}

enum { SAMPLES = 2001, PARTS = 4 };

static int follows_a_cosine(void)
{
    static TermProgram program;
    static double u[2 * PARTS * (SAMPLES - 1) + 1], q[SAMPLES], qd[SAMPLES];
    int failed = parse(&program, OSCILLATOR);
    const double omega = 2.0 * 3.141592653589793 * 5.0, step = 1e-3;
    const double theta[] = {1.0, 0.0, omega * omega}, q0[] = {1.0}, qd0[] = {0.0}, limit[] = {10.0};
    long diverged = 0;
    ms_simulate(&program, (MsShape){1, SAMPLES, PARTS, step}, theta, q0, qd0, u, limit, q, qd,
                &diverged);
    double worst = 0.0;
    for (long s = 0; s < SAMPLES; ++s) worst = fmax(worst, fabs(q[s] - cos(omega * s * step)));
    failed += check(diverged == -1 && worst < 1e-7, "free oscillation: worst error %.3g (< 1e-7), "
                    "diverged %ld", worst, diverged);
    return failed;
}

static int marks_a_diverging_run(void)
{
    static TermProgram program;
    static double u[2 * 2 * (2 * PARTS * (SAMPLES - 1) + 1)], q[2 * SAMPLES], qd[2 * SAMPLES];
    int failed = parse(&program, OSCILLATOR);
    /* two runs at once: negative damping (grows as exp(10 t)), then a stable one */
    const double theta[] = {1.0, -20.0, 100.0, 1.0, 20.0, 100.0};
    const double q0[] = {1e-3, 1e-3}, qd0[] = {0.0, 0.0}, limit[] = {1.0};
    long diverged[2] = {0, 0};
    ms_simulate(&program, (MsShape){2, SAMPLES, PARTS, 1e-3}, theta, q0, qd0, u, limit, q, qd,
                diverged);
    failed += check(diverged[0] > 0 && diverged[0] < SAMPLES && diverged[1] == -1,
                    "the unstable run diverges at sample %ld, the stable one never (%ld)",
                    diverged[0], diverged[1]);
    failed += check(q[SAMPLES - 1] == q[diverged[0] - 1] && fabs(q[SAMPLES - 1] - 1e-3) <= 1.0,
                    "held at its last good position %g", q[SAMPLES - 1]);
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"solves_the_mass_matrix", solves_the_mass_matrix},
        {"follows_a_cosine", follows_a_cosine},
        {"marks_a_diverging_run", marks_a_diverging_run},
    };
    return run_cases("test_model_simulation", cases, sizeof cases / sizeof cases[0], argc, argv);
}
