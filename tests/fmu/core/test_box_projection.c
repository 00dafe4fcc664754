/* Unit tests of the least squares inside a box (fmu/src/core/box_projection.h):
 * run as `test_box_projection CASE` (check.h). */
#include <math.h>

#include "check.h"

#include "box_projection.h"

#define N 6

static double objective(int p, double P[][N], const double x_hat[], const double x[])
{
    double f = 0.0;
    for (int i = 0; i < p; ++i)
        for (int j = 0; j < p; ++j) f += (x[i] - x_hat[i]) * P[i][j] * (x[j] - x_hat[j]);
    return f;
}

static int leaves_an_inside_estimate(void)
{
    const double P[N][N] = {{2.0, 0.5}, {0.5, 1.0}}, lower[] = {0.0, -INFINITY},
                 upper[] = {INFINITY, 3.0};
    double x[] = {1.0, 2.0};
    int held[2];
    const BpResult result = bp_project(2, &P[0][0], N, lower, upper, x, held);
    return check(result == BP_INSIDE && x[0] == 1.0 && x[1] == 2.0 && !held[0] && !held[1],
                 "inside: unchanged (result %d, x = %g %g)", result, x[0], x[1]);
}

/* Held at 0, the correlated unknown moves by -P10 / P11 times the shift. */
static int moves_the_correlated_unknown(void)
{
    const double P[N][N] = {{1.0, 0.9}, {0.9, 1.0}}, lower[] = {0.0, -INFINITY},
                 upper[] = {INFINITY, INFINITY};
    double x[] = {-1.0, 1.0};
    int held[2];
    const BpResult result = bp_project(2, &P[0][0], N, lower, upper, x, held);
    return check(result == BP_PROJECTED && x[0] == 0.0 && fabs(x[1] - 0.1) < 1e-15 &&
                     held[0] == -1 && held[1] == 0,
                 "x = %.17g %.17g (expected 0 and 0.1), held %d %d", x[0], x[1], held[0],
                 held[1]);
}

/* Random positive definite P and boxes: the minimum over every pattern of held
 * ends (3^6 solves by brute force) is what the active set finds. */
static int finds_the_minimum_of_every_pattern(void)
{
    unsigned state = 12345u;
    int failed = 0;
    for (int trial = 0; trial < 200; ++trial) {
        double A[N][N], P[N][N], x_hat[N], lower[N], upper[N];
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) {
                state = state * 1664525u + 1013904223u;
                A[i][j] = (double)(state >> 8) / 16777216.0 - 0.5;
            }
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) {
                P[i][j] = i == j ? 0.05 : 0.0;
                for (int k = 0; k < N; ++k) P[i][j] += A[k][i] * A[k][j];
            }
        for (int i = 0; i < N; ++i) {
            state = state * 1664525u + 1013904223u;
            x_hat[i] = 4.0 * ((double)(state >> 8) / 16777216.0 - 0.5);
            lower[i] = i % 3 == 0 ? -INFINITY : -0.5;
            upper[i] = i % 3 == 1 ? INFINITY : 0.7;
        }
        double x[N];
        int held[N];
        for (int i = 0; i < N; ++i) x[i] = x_hat[i];
        const BpResult result = bp_project(N, &P[0][0], N, lower, upper, x, held);
        int inside = result != BP_CLIPPED;
        for (int i = 0; i < N; ++i) inside &= lower[i] <= x[i] && x[i] <= upper[i];
        /* brute force: each pattern's solve by coordinate descent to convergence */
        double best = INFINITY;
        for (int pattern = 0; pattern < 729; ++pattern) {
            double y[N];
            int code = pattern, ends[N], possible = 1;
            for (int i = 0; i < N; ++i, code /= 3) {
                ends[i] = code % 3 - 1;
                possible &= ends[i] == 0 || isfinite(ends[i] < 0 ? lower[i] : upper[i]);
                y[i] = ends[i] < 0 ? lower[i] : ends[i] > 0 ? upper[i] : x_hat[i];
            }
            if (!possible) continue;
            for (int sweep = 0; sweep < 2000; ++sweep)
                for (int i = 0; i < N; ++i) {
                    if (ends[i]) continue;
                    double g = 0.0;
                    for (int j = 0; j < N; ++j) g += P[i][j] * (y[j] - x_hat[j]);
                    y[i] -= g / P[i][i];
                }
            int feasible = 1;
            for (int i = 0; i < N; ++i) feasible &= lower[i] - 1e-12 <= y[i] && y[i] <= upper[i] + 1e-12;
            if (feasible) best = fmin(best, objective(N, P, x_hat, y));
        }
        const double found = objective(N, P, x_hat, x);
        if (!inside || !(found <= best * (1.0 + 1e-9) + 1e-12)) {
            failed += check(0, "trial %d: result %d, inside %d, objective %.12g against the "
                            "best pattern's %.12g", trial, result, inside, found, best);
        }
    }
    return failed + check(failed == 0, "200 random problems: the box's minimum every time");
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"leaves_an_inside_estimate", leaves_an_inside_estimate},
        {"moves_the_correlated_unknown", moves_the_correlated_unknown},
        {"finds_the_minimum_of_every_pattern", finds_the_minimum_of_every_pattern},
    };
    return run_cases("test_box_projection", cases, sizeof cases / sizeof cases[0], argc, argv);
}
