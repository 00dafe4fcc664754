/* Prints the modelDescription.xml (FMI 2.0 or 3.0) or the sources'
 * buildDescription.xml of the model it is linked with, so that the C variable
 * table is the single source of truth.  build.sh compares the model
 * descriptions with the committed XML and stops if they differ.
 *
 * usage: describe_model fmi2|fmi3|build SOURCE_FILE... > OUT.xml
 * (source files relative to sources/: FMI 2 lists them in <SourceFiles>,
 * buildDescription.xml in its <SourceFileSet>) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../src/instance/model_interface.h"

#define MD MODEL_DESCRIPTOR

typedef struct {
    const char *name;
    int kg, m, s, rad;
} UnitDefinition;

static const UnitDefinition UNITS[] = {
    {"s", 0, 0, 1, 0},       {"rad", 0, 0, 0, 1},     {"rad/s", 0, 0, -1, 1},
    {"rad/s2", 0, 0, -2, 1}, {"N.m", 1, 2, -2, 0},    {"kg", 1, 0, 0, 0},
    {"m", 0, 1, 0, 0},       {"m/s2", 0, 1, -2, 0},   {"kg.m2", 1, 2, 0, 0},
    {"kg.m2/s", 1, 2, -1, 0}, {"N.m.s", 1, 2, -1, 0}, {"1/s", 0, 0, -1, 0},
    {"rad/s3", 0, 0, -3, 1}, {"Hz", 0, 0, -1, 0},
};
#define N_UNITS (sizeof UNITS / sizeof UNITS[0])

/* Shortest decimal that reads back as the same double. */
static const char *real_text(double value, char *buffer, size_t size)
{
    for (int digits = 15; digits <= 17; ++digits) {
        snprintf(buffer, size, "%.*g", digits, value);
        if (strtod(buffer, NULL) == value) break;
    }
    return buffer;
}

static void print_escaped(const char *text)
{
    for (const char *p = text; *p; ++p) {
        switch (*p) {
        case '&': fputs("&amp;", stdout); break;
        case '<': fputs("&lt;", stdout); break;
        case '>': fputs("&gt;", stdout); break;
        case '"': fputs("&quot;", stdout); break;
        default: putchar(*p);
        }
    }
}

static const char *causality_name(VariableCausality c)
{
    switch (c) {
    case CAUSALITY_PARAMETER: return "parameter";
    case CAUSALITY_CALCULATED_PARAMETER: return "calculatedParameter";
    case CAUSALITY_INPUT: return "input";
    default: return "output";
    }
}

static const char *variability_name(VariableVariability v)
{
    return v == VARIABILITY_FIXED ? "fixed" : v == VARIABILITY_DISCRETE ? "discrete" : "continuous";
}

static int unit_used(const char *unit)
{
    for (size_t v = 0; v < MD.n_variables; ++v)
        if (MD.variables[v].unit && strcmp(MD.variables[v].unit, unit) == 0) return 1;
    return 0;
}

static void print_units(void)
{
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const char *unit = MD.variables[v].unit;
        int known = !unit;
        for (size_t u = 0; unit && u < N_UNITS; ++u) known |= strcmp(UNITS[u].name, unit) == 0;
        if (!known) {
            fprintf(stderr, "describe_model: unit \"%s\" of %s has no definition\n", unit,
                    MD.variables[v].name);
            exit(1);
        }
    }
    puts("  <UnitDefinitions>");
    for (size_t u = 0; u < N_UNITS; ++u) {
        if (!unit_used(UNITS[u].name)) continue;
        printf("    <Unit name=\"%s\"><BaseUnit", UNITS[u].name);
        if (UNITS[u].kg) printf(" kg=\"%d\"", UNITS[u].kg);
        if (UNITS[u].m) printf(" m=\"%d\"", UNITS[u].m);
        if (UNITS[u].s) printf(" s=\"%d\"", UNITS[u].s);
        if (UNITS[u].rad) printf(" rad=\"%d\"", UNITS[u].rad);
        puts("/></Unit>");
    }
    puts("  </UnitDefinitions>");
}

static int has_start(const ModelVariable *var)
{
    return var->causality == CAUSALITY_PARAMETER || var->causality == CAUSALITY_INPUT;
}

static void print_variable(const ModelVariable *var, size_t e)
{
    char name[96];
    if (!var->rows) snprintf(name, sizeof name, "%s", var->name);
    else if (!var->cols) snprintf(name, sizeof name, "%s[%zu]", var->name, e + 1);
    else snprintf(name, sizeof name, "%s[%zu,%zu]", var->name, e / var->cols + 1, e % var->cols + 1);
    printf("    <ScalarVariable name=\"%s\" valueReference=\"%u\" causality=\"%s\" variability=\"%s\"",
           name, (unsigned)(var->vr + e), causality_name(var->causality),
           variability_name(var->variability));
    if (var->description) {
        fputs(" description=\"", stdout);
        print_escaped(var->description);
        putchar('"');
    }
    puts(">");
    const double start = var->starts ? var->starts[e] : var->start;
    char text[40];
    const char *type = var->type == TYPE_REAL ? "Real" : var->type == TYPE_INTEGER ? "Integer" : "Boolean";
    printf("      <%s", type);
    if (var->unit) printf(" unit=\"%s\"", var->unit);
    if (var->type != TYPE_BOOLEAN) {
        if (!isnan(var->min)) printf(" min=\"%s\"", real_text(var->min, text, sizeof text));
        if (!isnan(var->max)) printf(" max=\"%s\"", real_text(var->max, text, sizeof text));
    }
    if (has_start(var)) {
        if (var->type == TYPE_REAL) printf(" start=\"%s\"", real_text(start, text, sizeof text));
        else if (var->type == TYPE_INTEGER) printf(" start=\"%d\"", (int)start);
        else printf(" start=\"%s\"", start != 0.0 ? "true" : "false");
    }
    puts("/>");
    puts("    </ScalarVariable>");
}

static void print_log_categories(void)
{
    puts("  <LogCategories>");
    puts("    <Category name=\"logStatusWarning\" description=\"Warnings\"/>");
    puts("    <Category name=\"logStatusError\" description=\"Errors\"/>");
    puts("    <Category name=\"logAll\" description=\"Everything, including debug messages\"/>");
    puts("  </LogCategories>");
}

static void print_default_experiment(double h)
{
    char stop[40], tolerance[40], step[40];
    printf("  <DefaultExperiment startTime=\"0\" stopTime=\"%s\" tolerance=\"%s\" stepSize=\"%s\"/>\n",
           real_text(MD.default_stop_time, stop, sizeof stop),
           real_text(MD.default_tolerance, tolerance, sizeof tolerance), real_text(h, step, sizeof step));
}

/* ---- FMI 2.0: one ScalarVariable per element (value reference vr + e) -------- */

static void print_fmi2(double h, int n_files, char **files)
{
    puts("<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    printf("<fmiModelDescription fmiVersion=\"2.0\" modelName=\"%s\" guid=\"%s\"\n", MD.model_name, MD.guid);
    fputs("  description=\"", stdout);
    print_escaped(MD.description);
    puts("\"\n  generationTool=\"sto-fmu describe_model\" variableNamingConvention=\"structured\" "
         "numberOfEventIndicators=\"0\">");
    printf("  <CoSimulation modelIdentifier=\"%s\" canHandleVariableCommunicationStepSize=\"true\"\n"
           "    canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\"\n"
           "    canNotUseMemoryManagementFunctions=\"true\">\n", MD.model_identifier);
    puts("    <SourceFiles>");
    for (int i = 0; i < n_files; ++i) printf("      <File name=\"%s\"/>\n", files[i]);
    puts("    </SourceFiles>");
    puts("  </CoSimulation>");
    print_units();
    print_log_categories();
    print_default_experiment(h);
    puts("  <ModelVariables>");
    for (size_t v = 0; v < MD.n_variables; ++v)
        for (size_t e = 0; e < model_variable_count(&MD.variables[v]); ++e)
            print_variable(&MD.variables[v], e);
    puts("  </ModelVariables>");

    /* Outputs, then every output and calculated parameter as an initial unknown. */
    puts("  <ModelStructure>");
    for (int pass = 0; pass < 2; ++pass) {
        puts(pass == 0 ? "    <Outputs>" : "    <InitialUnknowns>");
        size_t index = 0;
        for (size_t v = 0; v < MD.n_variables; ++v) {
            const ModelVariable *var = &MD.variables[v];
            for (size_t e = 0; e < model_variable_count(var); ++e) {
                ++index;
                int listed = var->causality == CAUSALITY_OUTPUT ||
                             (pass == 1 && var->causality == CAUSALITY_CALCULATED_PARAMETER);
                if (listed) printf("      <Unknown index=\"%zu\"/>\n", index);
            }
        }
        puts(pass == 0 ? "    </Outputs>" : "    </InitialUnknowns>");
    }
    puts("  </ModelStructure>");
    puts("</fmiModelDescription>");
}

/* ---- FMI 3.0 -------------------------------------------------------------- */

static const char *fmi3_type_name(VariableType type)
{
    return type == TYPE_REAL ? "Float64" : type == TYPE_INTEGER ? "Int32" : "Boolean";
}

static void print_start_value(const ModelVariable *var, size_t e)
{
    const double start = var->starts ? var->starts[e] : var->start;
    char text[40];
    if (var->type == TYPE_REAL) fputs(real_text(start, text, sizeof text), stdout);
    else if (var->type == TYPE_INTEGER) printf("%d", (int)start);
    else fputs(start != 0.0 ? "true" : "false", stdout);
}

/* One variable, vectors and matrices as arrays (row-major, like the data block). */
static void print_variable3(const ModelVariable *var)
{
    const char *type = fmi3_type_name(var->type);
    printf("    <%s name=\"%s\" valueReference=\"%u\" causality=\"%s\" variability=\"%s\"", type,
           var->name, (unsigned)var->vr, causality_name(var->causality),
           variability_name(var->variability));
    if (var->description) {
        fputs(" description=\"", stdout);
        print_escaped(var->description);
        putchar('"');
    }
    char text[40];
    if (var->unit) printf(" unit=\"%s\"", var->unit);
    if (var->type != TYPE_BOOLEAN) {
        if (!isnan(var->min)) printf(" min=\"%s\"", real_text(var->min, text, sizeof text));
        if (!isnan(var->max)) printf(" max=\"%s\"", real_text(var->max, text, sizeof text));
    }
    if (has_start(var)) {
        fputs(" start=\"", stdout);
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            if (e) putchar(' ');
            print_start_value(var, e);
        }
        putchar('"');
    }
    if (!var->rows) {
        puts("/>");
        return;
    }
    puts(">");
    printf("      <Dimension start=\"%u\"/>\n", (unsigned)var->rows);
    if (var->cols) printf("      <Dimension start=\"%u\"/>\n", (unsigned)var->cols);
    printf("    </%s>\n", type);
}

static void print_fmi3(double h)
{
    puts("<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    printf("<fmiModelDescription fmiVersion=\"3.0\" modelName=\"%s\" instantiationToken=\"%s\"\n",
           MD.model_name, MD.guid);
    fputs("  description=\"", stdout);
    print_escaped(MD.description);
    puts("\"\n  generationTool=\"sto-fmu describe_model\" variableNamingConvention=\"structured\">");
    printf("  <CoSimulation modelIdentifier=\"%s\" canHandleVariableCommunicationStepSize=\"true\"\n"
           "    canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\"/>\n",
           MD.model_identifier);
    print_units();
    print_log_categories();
    print_default_experiment(h);
    puts("  <ModelVariables>");
    puts("    <Float64 name=\"time\" valueReference=\"0\" causality=\"independent\" "
         "variability=\"continuous\" description=\"Simulation time\"/>");
    for (size_t v = 0; v < MD.n_variables; ++v) print_variable3(&MD.variables[v]);
    puts("  </ModelVariables>");
    /* Outputs, then every output and calculated parameter as an initial unknown. */
    puts("  <ModelStructure>");
    for (int pass = 0; pass < 2; ++pass) {
        for (size_t v = 0; v < MD.n_variables; ++v) {
            const ModelVariable *var = &MD.variables[v];
            int listed = var->causality == CAUSALITY_OUTPUT ||
                         (pass == 1 && var->causality == CAUSALITY_CALCULATED_PARAMETER);
            if (listed)
                printf("    <%s valueReference=\"%u\"/>\n", pass == 0 ? "Output" : "InitialUnknown",
                       (unsigned)var->vr);
        }
    }
    puts("  </ModelStructure>");
    puts("</fmiModelDescription>");
}

/* ---- sources/buildDescription.xml (FMI 3.0 schema, shipped in both FMUs) ---- */

static void print_build_description(int n_files, char **files)
{
    puts("<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    puts("<fmiBuildDescription fmiVersion=\"3.0\">");
    printf("  <BuildConfiguration modelIdentifier=\"%s\">\n", MD.model_identifier);
    puts("    <SourceFileSet language=\"C11\">");
    for (int i = 0; i < n_files; ++i) printf("      <SourceFile name=\"%s\"/>\n", files[i]);
    puts("    </SourceFileSet>");
    puts("    <Library name=\"m\" external=\"true\" description=\"C math library (libm on Linux; "
         "part of the C runtime elsewhere)\"/>");
    puts("  </BuildConfiguration>");
    puts("</fmiBuildDescription>");
}

/* The default experiment's step is the model's internal step at its start values. */
static double default_step(void)
{
    void *data = calloc(1, MD.data_size);
    if (!data) exit(1);
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            double start = var->starts ? var->starts[e] : var->start;
            char *slot = (char *)data + var->offset;
            if (var->type == TYPE_REAL) ((double *)slot)[e] = start;
            else ((int *)slot)[e] = (int)start;
        }
    }
    const double h = MD.internal_step(data);
    free(data);
    return h;
}

int main(int argc, char **argv)
{
    const char *what = argc > 1 ? argv[1] : "";
    if (strcmp(what, "fmi2") == 0) print_fmi2(default_step(), argc - 2, argv + 2);
    else if (strcmp(what, "fmi3") == 0) print_fmi3(default_step());
    else if (strcmp(what, "build") == 0) print_build_description(argc - 2, argv + 2);
    else {
        fputs("usage: describe_model fmi2|fmi3|build SOURCE_FILE... > OUT.xml\n", stderr);
        return 2;
    }
    return 0;
}
