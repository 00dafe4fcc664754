/* A small FMI importer in plain C: runs an FMU binary's default experiment and
 * compares it with the reference result the FMU ships (FMI-LS-REF).  Built for
 * the target platform and run there (or under qemu-user / wine) by
 * tools/dist/check_platform.sh, so that a cross-compiled binary is executed,
 * not only linked.
 *
 *   run_reference PLAN BINARY
 *
 * PLAN (written by tools/dist/plan.py from the FMU) is plain text:
 *   fmi <2|3>
 *   token <GUID or instantiationToken>
 *   experiment <start> <stop> <step> <decimation> <tolerance>
 *   outputs <n>           then n lines "<value reference> <element count>"
 *   rows <m> <columns>    then m lines "<time> <value>..." (the reference, in output order)
 *
 * Exit status 0 when every reference value is matched within tolerance *
 * max(1, max |reference column|), 1 otherwise, 2 on errors (all printed). */
#if !defined(_WIN32)
#define _XOPEN_SOURCE 700 /* realpath */
#endif
#if defined(_WIN32)
#include <windows.h>
#else
#include <dlfcn.h>
#endif
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"

typedef struct {
    int fmi;
    char token[256];
    double start, stop, step, tolerance;
    long decimation;
    size_t n_outputs, n_values, n_rows;
    unsigned *vr, *count;
    double *reference; /* n_rows x (1 + n_values) */
} Plan;

static void die(const char *format, ...)
{
    va_list args;
    va_start(args, format);
    fputs("run_reference: ", stderr);
    vfprintf(stderr, format, args);
    fputc('\n', stderr);
    va_end(args);
    exit(2);
}

static void *xcalloc(size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size);
    if (!p) die("out of memory");
    return p;
}

static Plan read_plan(const char *path)
{
    Plan p;
    memset(&p, 0, sizeof p);
    FILE *f = fopen(path, "r");
    if (!f) die("cannot open %s", path);
    size_t columns = 0;
    if (fscanf(f, " fmi %d token %255s experiment %lf %lf %lf %ld %lf outputs %zu", &p.fmi,
               p.token, &p.start, &p.stop, &p.step, &p.decimation, &p.tolerance,
               &p.n_outputs) != 8)
        die("%s: bad header", path);
    p.vr = xcalloc(p.n_outputs, sizeof *p.vr);
    p.count = xcalloc(p.n_outputs, sizeof *p.count);
    for (size_t i = 0; i < p.n_outputs; ++i) {
        if (fscanf(f, "%u %u", &p.vr[i], &p.count[i]) != 2) die("%s: bad output %zu", path, i);
        p.n_values += p.count[i];
    }
    if (fscanf(f, " rows %zu %zu", &p.n_rows, &columns) != 2 || columns != 1 + p.n_values)
        die("%s: bad reference header", path);
    p.reference = xcalloc(p.n_rows * columns, sizeof *p.reference);
    for (size_t i = 0; i < p.n_rows * columns; ++i)
        if (fscanf(f, "%lf", &p.reference[i]) != 1) die("%s: short reference", path);
    fclose(f);
    return p;
}

/* ---- the library -------------------------------------------------------------- */

#if defined(_WIN32)
static void *library;
static void open_library(const char *path)
{
    library = (void *)LoadLibraryA(path);
    if (!library) die("cannot load %s (error %lu)", path, (unsigned long)GetLastError());
}
static void *symbol(const char *name)
{
    FARPROC f = GetProcAddress((HMODULE)library, name);
    if (!f) die("%s is not exported", name);
    void *p;
    memcpy(&p, &f, sizeof p); /* function to object pointer, as POSIX dlsym does */
    return p;
}
#else
static void *library;
static void open_library(const char *path)
{
    library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!library) die("cannot load %s: %s", path, dlerror());
}
static void *symbol(const char *name)
{
    void *p = dlsym(library, name);
    if (!p) die("%s is not exported", name);
    return p;
}
#endif

/* Looks up fmiXName as the declared type. */
#define LOAD(type, name) type *name; { void *p_ = symbol(#name); memcpy(&name, &p_, sizeof name); }

static void logger2(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                 fmi2String category, fmi2String message, ...)
{
    (void)env, (void)category;
    fprintf(stderr, "[%s] status %d: %s\n", instance ? instance : "", (int)status, message);
}

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                 fmi3String message)
{
    (void)env, (void)category;
    fprintf(stderr, "status %d: %s\n", (int)status, message);
}

/* ---- the default experiment ------------------------------------------------------- */

typedef struct {
    int fmi;
    void *instance;
    fmi2DoStepTYPE *do_step2;
    fmi2GetRealTYPE *get2;
    fmi3DoStepTYPE *do_step3;
    fmi3GetFloat64TYPE *get3;
} Runner;

/* The FMU's resources folder from its binary's path (<fmu>/binaries/<platform>/<file>):
 * a native path with a trailing separator (FMI 3) and a file: URI (FMI 2). */
static char RESOURCE_PATH[4096], RESOURCE_URI[4200];

static void find_resources(const char *binary)
{
    /* absolute, so that the FMI 2 URI names the same folder from anywhere */
#if defined(_WIN32)
    if (!_fullpath(RESOURCE_PATH, binary, sizeof RESOURCE_PATH - 16))
        die("cannot make %s absolute", binary);
#else
    if (strlen(binary) >= sizeof RESOURCE_PATH || !realpath(binary, RESOURCE_PATH))
        die("cannot make %s absolute", binary);
#endif
    if (strlen(RESOURCE_PATH) + 16 > sizeof RESOURCE_PATH) die("the binary's path is too long");
    for (int up = 0; up < 3; ++up) { /* the file, its platform and binaries/ */
        char *cut = NULL;
        for (char *c = RESOURCE_PATH; *c; ++c)
            if (*c == '/' || *c == '\\') cut = c;
        if (!cut) die("%s is not in <fmu>/binaries/<platform>/", binary);
        *cut = '\0';
    }
    const char separator = strchr(binary, '\\') ? '\\' : '/';
    const size_t root = strlen(RESOURCE_PATH);
    snprintf(RESOURCE_PATH + root, sizeof RESOURCE_PATH - root, "%cresources%c", separator,
             separator);
    /* file:///C:/x/resources/ or file:///x/resources/ (spaces as %20) */
    size_t at = (size_t)snprintf(RESOURCE_URI, sizeof RESOURCE_URI, "file://%s",
                                 RESOURCE_PATH[0] == '/' ? "" : "/");
    for (const char *c = RESOURCE_PATH; *c && at + 4 < sizeof RESOURCE_URI; ++c) {
        if (*c == ' ') at += (size_t)snprintf(RESOURCE_URI + at, 4, "%%20");
        else RESOURCE_URI[at++] = *c == '\\' ? '/' : *c;
    }
    RESOURCE_URI[at] = '\0';
}

static Runner start_fmi2(const Plan *p)
{
    static const fmi2CallbackFunctions callbacks = {logger2, NULL, NULL, NULL, NULL};
    LOAD(fmi2InstantiateTYPE, fmi2Instantiate)
    LOAD(fmi2SetupExperimentTYPE, fmi2SetupExperiment)
    LOAD(fmi2EnterInitializationModeTYPE, fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationModeTYPE, fmi2ExitInitializationMode)
    Runner r = {.fmi = 2};
    { LOAD(fmi2DoStepTYPE, fmi2DoStep) r.do_step2 = fmi2DoStep; }
    { LOAD(fmi2GetRealTYPE, fmi2GetReal) r.get2 = fmi2GetReal; }
    r.instance = fmi2Instantiate("run_reference", fmi2CoSimulation, p->token, RESOURCE_URI,
                                 &callbacks, fmi2False, fmi2False);
    if (!r.instance) die("fmi2Instantiate failed");
    if (fmi2SetupExperiment(r.instance, fmi2False, 0.0, p->start, fmi2True, p->stop) > fmi2Warning ||
        fmi2EnterInitializationMode(r.instance) > fmi2Warning ||
        fmi2ExitInitializationMode(r.instance) > fmi2Warning)
        die("FMI 2 initialization failed");
    return r;
}

static Runner start_fmi3(const Plan *p)
{
    LOAD(fmi3InstantiateCoSimulationTYPE, fmi3InstantiateCoSimulation)
    LOAD(fmi3EnterInitializationModeTYPE, fmi3EnterInitializationMode)
    LOAD(fmi3ExitInitializationModeTYPE, fmi3ExitInitializationMode)
    Runner r = {.fmi = 3};
    { LOAD(fmi3DoStepTYPE, fmi3DoStep) r.do_step3 = fmi3DoStep; }
    { LOAD(fmi3GetFloat64TYPE, fmi3GetFloat64) r.get3 = fmi3GetFloat64; }
    r.instance = fmi3InstantiateCoSimulation("run_reference", p->token, RESOURCE_PATH, fmi3False,
                                             fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                             logger3, NULL);
    if (!r.instance) die("fmi3InstantiateCoSimulation failed");
    if (fmi3EnterInitializationMode(r.instance, fmi3False, 0.0, p->start, fmi3True, p->stop) >
            fmi3Warning ||
        fmi3ExitInitializationMode(r.instance) > fmi3Warning)
        die("FMI 3 initialization failed");
    return r;
}

static void get_outputs(const Runner *r, const Plan *p, double *values)
{
    int status;
    if (r->fmi == 2) status = r->get2(r->instance, p->vr, p->n_outputs, values);
    else status = r->get3(r->instance, p->vr, p->n_outputs, values, p->n_values);
    if (status > 1) die("getting the outputs failed (status %d)", status);
}

static void do_step(const Runner *r, double t, double h)
{
    int status;
    if (r->fmi == 2) {
        status = r->do_step2(r->instance, t, h, fmi2True);
    } else {
        fmi3Boolean event, terminate, early;
        fmi3Float64 last;
        status = r->do_step3(r->instance, t, h, fmi3True, &event, &terminate, &early, &last);
        if (status <= 1 && (event || terminate || early || last != t + h))
            die("fmi3DoStep at %g: unexpected outputs", t);
    }
    if (status > 1) die("doStep at %.17g failed (status %d)", t, status);
}

int main(int argc, char **argv)
{
    if (argc != 3) die("usage: run_reference PLAN BINARY");
    Plan p = read_plan(argv[1]);
    open_library(argv[2]);
    find_resources(argv[2]);
    Runner r = p.fmi == 2 ? start_fmi2(&p) : start_fmi3(&p);
    const size_t columns = 1 + p.n_values;
    double *values = xcalloc(p.n_values, sizeof *values);
    double *scale = xcalloc(p.n_values, sizeof *scale);
    for (size_t j = 0; j < p.n_values; ++j) {
        scale[j] = 1.0;
        for (size_t i = 0; i < p.n_rows; ++i)
            scale[j] = fmax(scale[j], fabs(p.reference[i * columns + 1 + j]));
    }
    const long steps = lround((p.stop - p.start) / p.step);
    size_t row = 0, worst_column = 0;
    double worst = 0.0;
    for (long k = 0; k <= steps && row < p.n_rows; ++k) {
        const double t = k == steps ? p.stop : p.start + (double)k * p.step;
        if (k % p.decimation == 0 || k == steps) {
            const double *ref = &p.reference[row * columns];
            if (fabs(ref[0] - t) > 1e-9 * fmax(1.0, fabs(t)))
                die("reference row %zu is at t = %g, the run at %g", row, ref[0], t);
            get_outputs(&r, &p, values);
            for (size_t j = 0; j < p.n_values; ++j) {
                const double deviation = fabs(values[j] - ref[1 + j]) / scale[j];
                if (!(deviation <= worst)) worst = deviation, worst_column = j;
            }
            ++row;
        }
        if (k < steps) do_step(&r, t, p.start + (double)(k + 1) * p.step - t);
    }
    if (row != p.n_rows) die("compared %zu of %zu reference rows", row, p.n_rows);
    const int ok = worst <= p.tolerance;
    printf("FMI %d, %zu rows x %zu values: largest deviation %.3g (column %zu) of the scale, "
           "tolerance %.3g: %s\n", p.fmi, p.n_rows, p.n_values, worst, worst_column + 1,
           p.tolerance, ok ? "passed" : "FAILED");
    return ok ? 0 : 1;
}
