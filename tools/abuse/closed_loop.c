/* A closed loop of the project's FMUs through the plain FMI 2.0 C API, for
 * valgrind (tools/abuse/memcheck.sh): no Python, so every byte that memcheck
 * sees is the FMUs' or this driver's.
 *
 *   closed_loop PLAN SECONDS
 *
 * PLAN is a text file that tools/abuse/memcheck.sh writes from
 * harness/scenarios.py (the single source of the scenario's values):
 *
 *   step H
 *   fmu NAME MODEL_IDENTIFIER GUID LIBRARY      (in initialization order)
 *   real|integer|boolean NAME VR VALUE          (parameters, before initialization)
 *   link FROM_NAME FROM_VR TO_NAME TO_VR        (Real outputs to Real inputs)
 *   order NAME...                               (the step order)
 *   probe NAME VR                               (printed at the end)
 *
 * Besides the loop it exercises the rest of the API once per instance: FMU
 * states (get, serialize, deserialize, set, free), rejected calls (which log),
 * terminate, reset and a second initialization, then frees everything. */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MAX_FMUS 8
#define MAX_ITEMS 256

typedef struct {
    char name[64], identifier[64], guid[128], library[4096];
    void *dll;
    fmi2Component c;
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2TerminateTYPE *terminate;
    fmi2ResetTYPE *reset;
    fmi2GetRealTYPE *get_real;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetBooleanTYPE *set_boolean;
    fmi2DoStepTYPE *do_step;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2SerializedFMUstateSizeTYPE *serialized_size;
    fmi2SerializeFMUstateTYPE *serialize;
    fmi2DeSerializeFMUstateTYPE *deserialize;
} Fmu;

typedef struct { int fmu; char type; fmi2ValueReference vr; double value; } Parameter;
typedef struct { int from; fmi2ValueReference from_vr; int to; fmi2ValueReference to_vr; } Link;
typedef struct { int fmu; fmi2ValueReference vr; } Probe;

static Fmu fmus[MAX_FMUS];
static int n_fmus;
static Parameter parameters[MAX_ITEMS];
static int n_parameters;
static Link links[MAX_ITEMS];
static int n_links;
static int order[MAX_FMUS], n_order;
static Probe probes[MAX_ITEMS];
static int n_probes;
static double H;
static long logged;

static void die(const char *format, ...)
{
    va_list args;
    va_start(args, format);
    fprintf(stderr, "closed_loop: ");
    vfprintf(stderr, format, args);
    fprintf(stderr, "\n");
    va_end(args);
    exit(2);
}

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    ++logged;
    if (getenv("CLOSED_LOOP_VERBOSE"))
        fprintf(stderr, "[%s %d %s] %s\n", instance, (int)status, category, message);
}

static const fmi2CallbackFunctions CALLBACKS = {logger, calloc, free, NULL, NULL};

static int find_fmu(const char *name)
{
    for (int i = 0; i < n_fmus; ++i)
        if (strcmp(fmus[i].name, name) == 0) return i;
    die("unknown FMU %s", name);
    return -1;
}

static void *symbol(Fmu *f, const char *name)
{
    void *p = dlsym(f->dll, name);
    if (!p) die("%s: no %s", f->library, name);
    return p;
}

/* A symbol as the member's function pointer type (ISO C has no cast from void *). */
#define LOAD(f, member, name) \
    do { void *p_ = symbol(f, name); memcpy(&(f)->member, &p_, sizeof (f)->member); } while (0)

static void load(Fmu *f)
{
    f->dll = dlopen(f->library, RTLD_NOW | RTLD_LOCAL);
    if (!f->dll) die("dlopen %s: %s", f->library, dlerror());
    LOAD(f, instantiate, "fmi2Instantiate");
    LOAD(f, free_instance, "fmi2FreeInstance");
    LOAD(f, setup, "fmi2SetupExperiment");
    LOAD(f, enter, "fmi2EnterInitializationMode");
    LOAD(f, exit_init, "fmi2ExitInitializationMode");
    LOAD(f, terminate, "fmi2Terminate");
    LOAD(f, reset, "fmi2Reset");
    LOAD(f, get_real, "fmi2GetReal");
    LOAD(f, set_real, "fmi2SetReal");
    LOAD(f, set_integer, "fmi2SetInteger");
    LOAD(f, set_boolean, "fmi2SetBoolean");
    LOAD(f, do_step, "fmi2DoStep");
    LOAD(f, get_state, "fmi2GetFMUstate");
    LOAD(f, set_state, "fmi2SetFMUstate");
    LOAD(f, free_state, "fmi2FreeFMUstate");
    LOAD(f, serialized_size, "fmi2SerializedFMUstateSize");
    LOAD(f, serialize, "fmi2SerializeFMUstate");
    LOAD(f, deserialize, "fmi2DeSerializeFMUstate");
}

static void read_plan(const char *path)
{
    FILE *in = fopen(path, "r");
    if (!in) die("cannot open %s", path);
    char line[8192], word[64];
    while (fgets(line, sizeof line, in)) {
        if (sscanf(line, "%63s", word) != 1) continue;
        if (strcmp(word, "step") == 0) {
            if (sscanf(line, "%*s %lf", &H) != 1) die("bad line: %s", line);
        } else if (strcmp(word, "fmu") == 0) {
            if (n_fmus == MAX_FMUS) die("too many FMUs");
            Fmu *f = &fmus[n_fmus];
            if (sscanf(line, "%*s %63s %63s %127s %4095s", f->name, f->identifier, f->guid,
                       f->library) != 4)
                die("bad line: %s", line);
            ++n_fmus;
        } else if (strcmp(word, "real") == 0 || strcmp(word, "integer") == 0 ||
                   strcmp(word, "boolean") == 0) {
            char name[64];
            Parameter *p = &parameters[n_parameters];
            if (n_parameters == MAX_ITEMS ||
                sscanf(line, "%*s %63s %u %lf", name, &p->vr, &p->value) != 3)
                die("bad line: %s", line);
            p->fmu = find_fmu(name);
            p->type = word[0];
            ++n_parameters;
        } else if (strcmp(word, "link") == 0) {
            char from[64], to[64];
            Link *l = &links[n_links];
            if (n_links == MAX_ITEMS ||
                sscanf(line, "%*s %63s %u %63s %u", from, &l->from_vr, to, &l->to_vr) != 4)
                die("bad line: %s", line);
            l->from = find_fmu(from);
            l->to = find_fmu(to);
            ++n_links;
        } else if (strcmp(word, "order") == 0) {
            char *save = NULL, *token = strtok_r(line, " \t\n", &save);
            while ((token = strtok_r(NULL, " \t\n", &save))) {
                if (n_order == MAX_FMUS) die("order too long");
                order[n_order++] = find_fmu(token);
            }
        } else if (strcmp(word, "probe") == 0) {
            char name[64];
            Probe *p = &probes[n_probes];
            if (n_probes == MAX_ITEMS || sscanf(line, "%*s %63s %u", name, &p->vr) != 2)
                die("bad line: %s", line);
            p->fmu = find_fmu(name);
            ++n_probes;
        } else {
            die("unknown line: %s", line);
        }
    }
    fclose(in);
    if (!(H > 0) || !n_fmus || !n_order) die("%s: no step, FMU or order", path);
}

#define CHECK(call, what, f)                                                                 \
    do {                                                                                     \
        fmi2Status status_ = (call);                                                         \
        if (status_ > fmi2Warning) die("%s: %s returned %d", (f)->name, what, (int)status_); \
    } while (0)

static void set_parameters(int i)
{
    Fmu *f = &fmus[i];
    for (int k = 0; k < n_parameters; ++k) {
        const Parameter *p = &parameters[k];
        if (p->fmu != i) continue;
        if (p->type == 'r') {
            CHECK(f->set_real(f->c, &p->vr, 1, &p->value), "fmi2SetReal", f);
        } else {
            const fmi2Integer v = (fmi2Integer)p->value;
            if (p->type == 'i') CHECK(f->set_integer(f->c, &p->vr, 1, &v), "fmi2SetInteger", f);
            else CHECK(f->set_boolean(f->c, &p->vr, 1, &v), "fmi2SetBoolean", f);
        }
    }
}

/* Initialization in data-flow order: inputs from already initialized FMUs. */
static void initialize_all(double t0)
{
    for (int i = 0; i < n_fmus; ++i) {
        Fmu *f = &fmus[i];
        CHECK(f->setup(f->c, fmi2False, 0.0, t0, fmi2False, 0.0), "fmi2SetupExperiment", f);
        CHECK(f->enter(f->c), "fmi2EnterInitializationMode", f);
        set_parameters(i);
        for (int l = 0; l < n_links; ++l) {
            if (links[l].to != i || links[l].from >= i) continue;
            const Fmu *src = &fmus[links[l].from];
            double value;
            CHECK(src->get_real(src->c, &links[l].from_vr, 1, &value), "fmi2GetReal", src);
            CHECK(f->set_real(f->c, &links[l].to_vr, 1, &value), "fmi2SetReal", f);
        }
        CHECK(f->exit_init(f->c), "fmi2ExitInitializationMode", f);
    }
}

static void run(double t0, long steps)
{
    for (long k = 0; k < steps; ++k) {
        const double t = t0 + (double)k * H;
        for (int o = 0; o < n_order; ++o) {
            Fmu *f = &fmus[order[o]];
            for (int l = 0; l < n_links; ++l) {
                if (links[l].to != order[o]) continue;
                const Fmu *src = &fmus[links[l].from];
                double value;
                CHECK(src->get_real(src->c, &links[l].from_vr, 1, &value), "fmi2GetReal", src);
                CHECK(f->set_real(f->c, &links[l].to_vr, 1, &value), "fmi2SetReal", f);
            }
            CHECK(f->do_step(f->c, t, H, fmi2False), "fmi2DoStep", f);
        }
    }
}

static double probe(const Probe *p)
{
    const Fmu *f = &fmus[p->fmu];
    double value;
    CHECK(f->get_real(f->c, &p->vr, 1, &value), "fmi2GetReal", f);
    return value;
}

/* FMU state round trip and rejected calls on one instance (at time t). */
static void exercise(Fmu *f, double t)
{
    fmi2FMUstate state = NULL, copy = NULL;
    size_t size = 0;
    CHECK(f->get_state(f->c, &state), "fmi2GetFMUstate", f);
    CHECK(f->get_state(f->c, &state), "fmi2GetFMUstate (reuse)", f);
    CHECK(f->serialized_size(f->c, state, &size), "fmi2SerializedFMUstateSize", f);
    fmi2Byte *bytes = malloc(size);
    if (!bytes) die("out of memory");
    CHECK(f->serialize(f->c, state, bytes, size), "fmi2SerializeFMUstate", f);
    CHECK(f->deserialize(f->c, bytes, size, &copy), "fmi2DeSerializeFMUstate", f);
    bytes[size / 2] ^= 1;
    if (f->deserialize(f->c, bytes, size, &copy) != fmi2Error) die("%s: flipped bit accepted", f->name);
    if (f->deserialize(f->c, bytes, size - 1, &copy) != fmi2Error) die("%s: short state accepted", f->name);
    const fmi2ValueReference unknown = 0xFFFFFFFFu;
    double value;
    if (f->get_real(f->c, &unknown, 1, &value) != fmi2Error) die("%s: unknown vr accepted", f->name);
    if (f->do_step(f->c, t, -1.0, fmi2False) != fmi2Error) die("%s: negative step accepted", f->name);
    CHECK(f->set_state(f->c, copy), "fmi2SetFMUstate", f); /* out of the Error state */
    CHECK(f->do_step(f->c, t, H, fmi2False), "fmi2DoStep after restore", f);
    CHECK(f->set_state(f->c, state), "fmi2SetFMUstate", f);
    CHECK(f->free_state(f->c, &copy), "fmi2FreeFMUstate", f);
    free(bytes);
    /* `state` is left for fmi2FreeInstance to free */
}

int main(int argc, char **argv)
{
    if (argc != 3) die("usage: closed_loop PLAN SECONDS");
    read_plan(argv[1]);
    const double seconds = atof(argv[2]);
    const long steps = (long)llround(seconds / H);
    for (int i = 0; i < n_fmus; ++i) {
        Fmu *f = &fmus[i];
        load(f);
        f->c = f->instantiate(f->name, fmi2CoSimulation, f->guid, NULL, &CALLBACKS, fmi2False,
                              fmi2False);
        if (!f->c) die("%s: fmi2Instantiate returned NULL", f->name);
    }
    initialize_all(0.0);
    run(0.0, steps / 2);
    for (int i = 0; i < n_fmus; ++i) exercise(&fmus[i], (double)(steps / 2) * H);
    run((double)(steps / 2) * H, steps - steps / 2);
    printf("after %.6g s (%ld macro steps of %g s):\n", (double)steps * H, steps, H);
    for (int p = 0; p < n_probes; ++p) {
        const double v = probe(&probes[p]);
        printf("  %s[vr %u] = %.10g\n", fmus[probes[p].fmu].name, probes[p].vr, v);
        if (!isfinite(v)) die("probe %d is not finite", p);
    }
    /* the end of a life, a reset and a second, short one */
    for (int i = 0; i < n_fmus; ++i) {
        Fmu *f = &fmus[i];
        CHECK(f->terminate(f->c), "fmi2Terminate", f);
        CHECK(f->reset(f->c), "fmi2Reset", f);
    }
    initialize_all(0.0);
    run(0.0, steps < 1000 ? steps : 1000);
    for (int i = 0; i < n_fmus; ++i) {
        fmus[i].free_instance(fmus[i].c);
        dlclose(fmus[i].dll);
    }
    printf("  %ld messages logged\n", logged);
    return 0;
}
