/* Drives the RobotObserver model through its FMI 2.0 API, linked in directly
 * (no FMU, no dlopen), for the cost of its whole internal step: the observer
 * with the rigid-body forward dynamics, the regression and the identifier
 * (bench/perf/robot_step_cost.py --fmu):
 *
 *     robot_fmu_step PARAMETERS TRAJECTORY WARMUP STEPS CALLS
 *
 * PARAMETERS: line 1 "GUID h n"; then one line per parameter "R|I|B vr value"
 *             (written by robot_step_cost.py from the SSP parameter set of
 *             `python -m harness robot-fmu-parameters` and the model description).
 * TRAJECTORY: line 1 the number of rows; then per row q[1..n] u[1..n], one row
 *             per sample h (a moving robot: positions and its torques).
 * WARMUP:     doSteps of H = h first (past t_id: the identifier then runs).
 * STEPS:      internal steps per measured fmi2DoStep: H = STEPS * h.
 * CALLS:      measured fmi2DoStep calls; the inputs are set before each (the
 *             sample at the communication point, held over H).
 *
 * Prints the wall time of the measured calls per internal step (fmi2SetReal of
 * the inputs included), that of the slowest call, and the outcome: status,
 * identifier_active, converged, and n and base_count as the FMU has them (the
 * parameters reached it); then the doStep (0-based, warm-up included) after
 * which identifier_active first read 1, and those after which gamma_trace
 * changed (a solve with statistics published; the first MAX_PUBLISHED).
 * Callgrind counts with --toggle-collect=fmi2DoStep; the difference of two runs
 * with CALLS and 2 CALLS removes the warm-up and the initialization. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

#define MAX_N 7
/* Value references, fmu/src/models/RobotObserver/model.c (docs/robots.md). */
enum { VR_N = 2, VR_BASE_COUNT = 4, VR_Q = 600, VR_U = 610, VR_GAMMA_TRACE = 1000,
       VR_IDENTIFIER_ACTIVE = 1002, VR_CONVERGED = 1003 };
#define MAX_PUBLISHED 16 /* publications of the statistics recorded */

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    fprintf(stderr, "[%s] %s %d: %s\n", category, name, (int)status, message);
}

static void fail(const char *what)
{
    fprintf(stderr, "robot_fmu_step: %s\n", what);
    exit(1);
}

static void check(fmi2Status status, const char *what)
{
    if (status > fmi2Warning) fail(what);
}

/* Sets the parameters of the file after its first line; returns 0, or -1 on a bad line. */
static int set_parameters(fmi2Component c, FILE *f)
{
    char kind;
    unsigned vr;
    double value;
    int read;
    while ((read = fscanf(f, " %c %u %lf", &kind, &vr, &value)) == 3) {
        const fmi2ValueReference ref = vr;
        fmi2Status status;
        if (kind == 'R') {
            status = fmi2SetReal(c, &ref, 1, &value);
        } else if (kind == 'I') {
            const fmi2Integer v = (fmi2Integer)value;
            status = fmi2SetInteger(c, &ref, 1, &v);
        } else if (kind == 'B') {
            const fmi2Boolean v = value != 0.0 ? fmi2True : fmi2False;
            status = fmi2SetBoolean(c, &ref, 1, &v);
        } else {
            return -1;
        }
        if (status > fmi2Warning) {
            fprintf(stderr, "robot_fmu_step: setting %c %u = %g failed\n", kind, vr, value);
            return -1;
        }
    }
    return read == EOF ? 0 : -1;
}

/* What the calls published: the doStep (0-based) after which identifier_active
 * first read 1, and those after which gamma_trace changed. */
typedef struct {
    long calls, started, published[MAX_PUBLISHED];
    int n_published;
    double trace;
} Watch;

static const fmi2ValueReference VR_TRACE = VR_GAMMA_TRACE, VR_ACTIVE = VR_IDENTIFIER_ACTIVE;

static void watch(Watch *w, fmi2Component c)
{
    double trace = w->trace;
    fmi2Boolean active = fmi2False;
    check(fmi2GetReal(c, &VR_TRACE, 1, &trace), "fmi2GetReal of gamma_trace");
    check(fmi2GetBoolean(c, &VR_ACTIVE, 1, &active), "fmi2GetBoolean of identifier_active");
    if (active && w->started < 0) w->started = w->calls;
    if (trace != w->trace && w->n_published < MAX_PUBLISHED)
        w->published[w->n_published++] = w->calls;
    w->trace = trace;
    ++w->calls;
}

static double *read_trajectory(const char *path, int n, long *rows)
{
    FILE *f = fopen(path, "r");
    if (!f || fscanf(f, "%ld", rows) != 1 || *rows < 1) fail("cannot read the trajectory");
    double *x = malloc((size_t)*rows * 2 * (size_t)n * sizeof *x);
    if (!x) fail("out of memory");
    for (long k = 0; k < *rows * 2 * n; ++k)
        if (fscanf(f, "%lf", &x[k]) != 1) fail("the trajectory is short");
    fclose(f);
    return x;
}

static double elapsed_ns(const struct timespec *from, const struct timespec *to)
{
    return (double)(to->tv_sec - from->tv_sec) * 1e9 + (double)(to->tv_nsec - from->tv_nsec);
}

static void set_inputs(fmi2Component c, int n, const double *row)
{
    fmi2ValueReference vr[2 * MAX_N];
    for (int i = 0; i < n; ++i) {
        vr[i] = VR_Q + (fmi2ValueReference)i;
        vr[n + i] = VR_U + (fmi2ValueReference)i;
    }
    check(fmi2SetReal(c, vr, (size_t)(2 * n), row), "fmi2SetReal of q and u");
}

int main(int argc, char **argv)
{
    if (argc != 6) {
        fprintf(stderr, "usage: robot_fmu_step PARAMETERS TRAJECTORY WARMUP STEPS CALLS\n");
        return 2;
    }
    const long warmup = atol(argv[3]), steps = atol(argv[4]), calls = atol(argv[5]);
    if (warmup < 0 || steps < 1 || calls < 1) fail("WARMUP >= 0, STEPS >= 1, CALLS >= 1");
    FILE *f = fopen(argv[1], "r");
    char guid[128];
    double h = 0.0;
    int n = 0;
    if (!f || fscanf(f, "%127s %lf %d", guid, &h, &n) != 3 || !(h > 0.0) || n < 1 || n > MAX_N)
        fail("cannot read the parameters' first line (GUID h n)");
    long rows = 0;
    const double *x = read_trajectory(argv[2], n, &rows);

    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("robot", fmi2CoSimulation, guid, NULL, &callbacks,
                                      fmi2False, fmi2False);
    if (!c) fail("fmi2Instantiate failed");
    check(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), "fmi2SetupExperiment");
    if (set_parameters(c, f) != 0) fail("a parameter line is not 'R|I|B vr value'");
    fclose(f);
    check(fmi2EnterInitializationMode(c), "fmi2EnterInitializationMode");
    set_inputs(c, n, x);
    check(fmi2ExitInitializationMode(c), "fmi2ExitInitializationMode");

    /* Through a volatile pointer, as bench/perf/step_driver.c: fmi2DoStep stays a
     * function of its own for callgrind's --toggle-collect. */
    fmi2DoStepTYPE *volatile do_step = fmi2DoStep;
    fmi2Status status = fmi2OK;
    long k = 0; /* samples done */
    Watch watched = {.started = -1};
    check(fmi2GetReal(c, &VR_TRACE, 1, &watched.trace), "fmi2GetReal of gamma_trace");
    for (long w = 0; w < warmup && status <= fmi2Warning; ++w, ++k) {
        set_inputs(c, n, x + (k % rows) * 2 * n);
        status = do_step(c, (double)k * h, h, fmi2True);
        watch(&watched, c);
    }
    const double H = (double)steps * h;
    struct timespec start, before, after;
    double slowest = 0.0, total = 0.0; /* [ns] the slowest call, all calls */
    clock_gettime(CLOCK_MONOTONIC, &start);
    before = start;
    for (long call = 0; call < calls && status <= fmi2Warning; ++call, k += steps) {
        set_inputs(c, n, x + (k % rows) * 2 * n);
        status = do_step(c, (double)k * h, H, fmi2True);
        clock_gettime(CLOCK_MONOTONIC, &after);
        const double call_ns = elapsed_ns(&before, &after);
        if (call_ns > slowest) slowest = call_ns;
        total += call_ns;
        watch(&watched, c); /* outside the timed interval */
        clock_gettime(CLOCK_MONOTONIC, &before);
    }
    const double ns = total;

    const fmi2ValueReference vr[2] = {VR_IDENTIFIER_ACTIVE, VR_CONVERGED};
    fmi2Boolean flags[2] = {0, 0};
    const fmi2ValueReference vr_sizes[2] = {VR_N, VR_BASE_COUNT};
    fmi2Integer sizes[2] = {0, 0};
    check(fmi2GetBoolean(c, vr, 2, flags), "fmi2GetBoolean");
    check(fmi2GetInteger(c, vr_sizes, 2, sizes), "fmi2GetInteger");
    printf("ns_per_step=%.1f slowest_call_ns=%.0f status=%d identifier_active=%d converged=%d "
           "n=%d base_count=%d\n", ns / (double)(steps * calls), slowest, (int)status,
           (int)flags[0], (int)flags[1], (int)sizes[0], (int)sizes[1]);
    printf("identifier_started=%ld statistics_published=", watched.started);
    for (int i = 0; i < watched.n_published; ++i)
        printf("%s%ld", i ? "," : "", watched.published[i]);
    printf("\n");
    fmi2FreeInstance(c);
    free((void *)x);
    return status > fmi2Warning;
}
