/* Unit tests of the energy check of a model file's equations
 * (fmu/src/core/model_damping.h): run as `test_model_damping CASE` (check.h). */
#include <math.h>
#include <string.h>

#include "check.h"

#include "model_damping.h"

/* m q'' + Fv q' + Fc sign(q') + k q = u: theta = [m, Fv, Fc, k]. */
static const char DRIVE[] =
    "sto-term-program 1\n"
    "sizes 1 1 4\n"
    "constants 0\n"
    "nominal 1 0 0 0\n"
    "scale 1 1 1 1\n"
    "entry 0 0 1  3 0\n"
    "entry 0 1 1  2 0\n"
    "entry 0 2 2  2 0  15 0\n"
    "entry 0 3 1  1 0\n"
    "entry 0 4 1  4 0\n";

/* Two masses with a damper between them: m1 q1'' + c (q1' - q2') = u,
 * m2 q2'' + c (q2' - q1') + c2 q2' = 0, theta = [m1, m2, c, c2]; the damper's
 * matrix [[c, -c], [-c, c + c2]] is positive semidefinite for c, c2 >= 0. */
static const char TWO_MASSES[] =
    "sto-term-program 1\n"
    "sizes 2 1 4\n"
    "constants 1 0\n"
    "nominal 1 1 0 0\n"
    "scale 1 1 1 1\n"
    "entry 0 0 1  3 0\n"
    "entry 0 1 1  0 0\n"
    "entry 0 2 4  2 0  2 1  8 0  5 0\n"
    "entry 0 3 1  0 0\n"
    "entry 0 4 1  4 0\n"
    "entry 1 0 1  0 0\n"
    "entry 1 1 1  3 1\n"
    "entry 1 2 4  2 1  2 0  8 0  5 0\n"
    "entry 1 3 1  2 1\n"
    "entry 1 4 1  0 0\n";

static int energy(const char *text, const double theta[], int *which, MdDamping *damping)
{
    static TermProgram program;
    char error[256] = "";
    if (tp_parse(&program, text, strlen(text), error, sizeof error))
        return check(0, "the program parses ('%s')", error);
    const double q[2] = {0.3, -0.2}, u[1] = {1.5};
    if (md_damping(&program, theta, q, u, damping)) return check(0, "finite damping");
    *which = md_creates_energy(program.n, damping);
    return 0;
}

static int tells_the_friction_signs(void)
{
    static const struct {
        double theta[4];
        int expected;
        const char *what;
    } cases[] = {
        {{1.0, 0.2, 0.5, 4.0}, 0, "viscous and Coulomb friction take energy"},
        {{1.0, 0.0, 0.0, 4.0}, 0, "no friction: neither takes nor gives"},
        {{1.0, 0.2, 0.5, -4.0}, 0, "a negative stiffness is an unstable equilibrium, not energy"},
        {{1.0, -1e-3, 0.5, 4.0}, 1, "a negative viscous friction gives energy"},
        {{1.0, 0.2, -1e-3, 4.0}, 1, "a negative Coulomb level gives energy"},
    };
    int failed = 0;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        int which = -1;
        MdDamping damping;
        failed += energy(DRIVE, cases[c].theta, &which, &damping);
        failed += check(which == cases[c].expected && fabs(damping.D[0][0] - cases[c].theta[1]) <=
                            1e-6 * (1.0 + fabs(cases[c].theta[1])) &&
                            fabs(damping.coulomb[0] - cases[c].theta[2]) <= 1e-9,
                        "%s: %d (expected %d), damping %g, Coulomb level %g", cases[c].what, which,
                        cases[c].expected, damping.D[0][0], damping.coulomb[0]);
    }
    return failed;
}

static int checks_the_coupled_damping_as_a_matrix(void)
{
    int failed = 0, which = -1;
    MdDamping damping;
    const double passive[4] = {1.0, 2.0, 0.5, 0.1};
    failed += energy(TWO_MASSES, passive, &which, &damping);
    failed += check(which == 0 && fabs(damping.D[0][1] + 0.5) < 1e-6 &&
                        fabs(damping.D[1][1] - 0.6) < 1e-6,
                    "a damper between the masses takes energy (%d; D = [%g %g; %g %g])", which,
                    damping.D[0][0], damping.D[0][1], damping.D[1][0], damping.D[1][1]);
    /* every diagonal entry positive, but c2 < 0 makes [[c, -c], [-c, c + c2]] indefinite */
    const double active[4] = {1.0, 2.0, 0.5, -0.1};
    failed += energy(TWO_MASSES, active, &which, &damping);
    failed += check(which == 2 && damping.D[1][1] > 0.0,
                    "c2 = -0.1 gives energy though each diagonal entry is positive (%d, D22 = %g)",
                    which, damping.D[1][1]);
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"tells_the_friction_signs", tells_the_friction_signs},
        {"checks_the_coupled_damping_as_a_matrix", checks_the_coupled_damping_as_a_matrix},
    };
    return run_cases("test_model_damping", cases, sizeof cases / sizeof cases[0], argc, argv);
}
