/* Drives the SuperTwistingObserver model through its FMI 2.0 API, linked in
 * directly (no FMU, no dlopen), for counting instructions per internal step:
 *
 *     step_driver CONFIG SCHEME [STEPS [CALLS]]
 *
 * CONFIG: joint-off | joint-lsm | joint-mff   (n = 1, built-in joint, 3 regressors;
 *                                               MFF with the default mff_drift = true)
 *         ext-lsm | ext-mff                    (n = 4, external model, l = 8, all identified;
 *                                               MFF with mff_drift = false: it needs 2 m <= 8)
 * SCHEME: 1  the paper: scheme 1, identifier_form 1, filter_regressor false,
 *            identifier_start 0 (at t_id = 0)
 *         2  scheme 2, identifier_form 2, filter_regressor true, identifier_start 1
 *            (once converged), identify_b false (the defaults before scheme 3)
 *         3  the FMU's defaults: scheme 3 (noise-adaptive), identify_b true
 * STEPS:  internal steps per fmi2DoStep (default 10000): H = STEPS * h.
 * CALLS:  number of fmi2DoStep calls (default 1); CALLS = 10000 with STEPS = 1
 *         is the closed-loop harness's case H = h (a communication point per step).
 *
 * Inputs are constants (y, u, F, phi nonzero).  One fmi2DoStep of H runs
 * STEPS internal steps; bench/perf/step_instructions.sh runs this under
 * callgrind --toggle-collect=fmi2DoStep and divides by STEPS.  Prints the
 * outcome (status, identifier_active, converged, x2_hat[1]) to stdout. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define GUID "{5d0c3f0e-7b7a-4c52-9d5e-2f1a6b8e9c01}"

/* Value references, fmu/src/models/SuperTwistingObserver/model.c (docs/observer.md). */
enum {
    VR_H = 1, VR_N = 2, VR_NOMINAL_MODEL = 3, VR_SCHEME = 4, VR_IDENTIFIER = 5, VR_L = 6,
    VR_THETA_NOMINAL = 40, VR_T_ID = 80, VR_IDENTIFY = 83, VR_IDENTIFIER_FORM = 110,
    VR_IDENTIFIER_START = 111, VR_FILTER_REGRESSOR = 112, VR_MFF_DRIFT = 114, VR_IDENTIFY_B = 115,
    VR_Y = 200, VR_U = 204, VR_F = 208, VR_PHI = 212,
    VR_X2_HAT = 304, VR_IDENTIFIER_ACTIVE = 361, VR_CONVERGED = 362
};

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    fprintf(stderr, "[%s] %s %d: %s\n", category, name, (int)status, message);
}

static fmi2Component component;

static void check(fmi2Status status, const char *what)
{
    if (status > fmi2Warning) {
        fprintf(stderr, "step_driver: %s failed (status %d)\n", what, (int)status);
        exit(1);
    }
}

static void set_real(fmi2ValueReference vr, double value)
{
    check(fmi2SetReal(component, &vr, 1, &value), "fmi2SetReal");
}

static void set_int(fmi2ValueReference vr, int value)
{
    fmi2Integer v = value;
    check(fmi2SetInteger(component, &vr, 1, &v), "fmi2SetInteger");
}

static void set_bool(fmi2ValueReference vr, int value)
{
    fmi2Boolean v = value ? fmi2True : fmi2False;
    check(fmi2SetBoolean(component, &vr, 1, &v), "fmi2SetBoolean");
}

static void usage(void)
{
    fprintf(stderr, "usage: step_driver joint-off|joint-lsm|joint-mff|ext-lsm|ext-mff 1|2 "
                    "[STEPS]\n");
    exit(2);
}

int main(int argc, char **argv)
{
    if (argc < 3) usage();
    const char *config = argv[1];
    const int scheme = atoi(argv[2]);
    const long steps = argc > 3 ? atol(argv[3]) : 10000;
    const long calls = argc > 4 ? atol(argv[4]) : 1;
    const int external = strncmp(config, "ext-", 4) == 0;
    const char *kind = config + (external ? 4 : 6);
    if ((!external && strncmp(config, "joint-", 6) != 0) || (scheme < 1 || scheme > 3) ||
        steps < 1 || calls < 1)
        usage();
    const int identifier = strcmp(kind, "off") == 0 ? 0 : strcmp(kind, "lsm") == 0 ? 1
                           : strcmp(kind, "mff") == 0 ? 2 : -1;
    if (identifier < 0 || (external && identifier == 0)) usage();

    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    component = fmi2Instantiate("observer", fmi2CoSimulation, GUID, NULL, &callbacks, fmi2False,
                                fmi2False);
    if (!component) {
        fprintf(stderr, "step_driver: fmi2Instantiate failed\n");
        return 1;
    }
    const double h = 1e-4;
    check(fmi2SetupExperiment(component, fmi2False, 0.0, 0.0, fmi2False, 0.0),
          "fmi2SetupExperiment");
    set_real(VR_H, h);
    set_int(VR_SCHEME, scheme);
    set_int(VR_IDENTIFIER, identifier);
    set_real(VR_T_ID, 0.0);
    if (scheme == 1) { /* the paper's method exactly */
        set_int(VR_IDENTIFIER_FORM, 1);
        set_bool(VR_FILTER_REGRESSOR, 0);
        set_int(VR_IDENTIFIER_START, 0);
    }
    if (scheme <= 2) set_bool(VR_IDENTIFY_B, 0); /* the joint's m = 3 of the earlier counts */
    int n = 1;
    if (external) {
        n = 4;
        set_int(VR_NOMINAL_MODEL, 2);
        set_int(VR_N, n);
        set_int(VR_L, 8);
        for (int k = 0; k < 8; ++k) set_bool(VR_IDENTIFY + k, 1);
        if (identifier == 2 && scheme >= 2) set_bool(VR_MFF_DRIFT, 0); /* needs 2 m <= 8 */
        for (int i = 0; i < n; ++i)
            for (int k = 0; k < 8; ++k)
                set_real(VR_THETA_NOMINAL + 8 * i + k, 0.01 * (i + 1) * (k + 1));
    } /* joint: nominal_model 1, n 1, identify[1..3] by default (m = 3) */
    check(fmi2EnterInitializationMode(component), "fmi2EnterInitializationMode");
    for (int i = 0; i < n; ++i) set_real(VR_Y + i, 0.1 * (i + 1));
    set_real(VR_U, 0.5);
    if (external) {
        for (int i = 0; i < n; ++i) set_real(VR_F + i, -0.3 * (i + 1));
        for (int k = 0; k < 8; ++k) set_real(VR_PHI + k, 0.2 + 0.1 * k);
    }
    check(fmi2ExitInitializationMode(component), "fmi2ExitInitializationMode");

    /* The measured calls: CALLS communication steps of STEPS internal steps.
     * Called through a volatile pointer so that fmi2DoStep stays a function of
     * its own (callgrind --toggle-collect needs it) even when built with -flto. */
    fmi2DoStepTYPE *volatile do_step = fmi2DoStep;
    const double H = (double)steps * h;
    fmi2Status status = fmi2OK;
    for (long c = 0; c < calls && status <= fmi2Warning; ++c)
        status = do_step(component, (double)c * H, H, fmi2True);

    fmi2ValueReference vr[2] = {VR_IDENTIFIER_ACTIVE, VR_CONVERGED};
    fmi2Boolean flags[2] = {0, 0};
    double x2 = 0.0;
    fmi2ValueReference vr_x2 = VR_X2_HAT;
    fmi2GetBoolean(component, vr, 2, flags);
    fmi2GetReal(component, &vr_x2, 1, &x2);
    printf("config=%s scheme=%d steps=%ld calls=%ld status=%d identifier_active=%d "
           "converged=%d x2_hat[1]=%.6g\n", config, scheme, steps, calls, (int)status,
           (int)flags[0], (int)flags[1], x2);
    fmi2FreeInstance(component);
    return status > fmi2Warning;
}
