/* Prints the modelDescription.xml of the model it is linked with, so that
 * the C variable table is the single source of truth.  build.sh compares the
 * output with the committed XML and stops if they differ.
 *
 * usage: describe_model SOURCE_FILE... > modelDescription.xml
 * (the source files are listed in <SourceFiles>, relative to sources/) */
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
    {"rad/s3", 0, 0, -3, 1},
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

int main(int argc, char **argv)
{
    /* The default experiment's step is the model's internal step at its start values. */
    void *data = calloc(1, MD.data_size);
    if (!data) return 1;
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
    for (int i = 1; i < argc; ++i) printf("      <File name=\"%s\"/>\n", argv[i]);
    puts("    </SourceFiles>");
    puts("  </CoSimulation>");
    print_units();
    puts("  <LogCategories>");
    puts("    <Category name=\"logStatusWarning\" description=\"Warnings\"/>");
    puts("    <Category name=\"logStatusError\" description=\"Errors\"/>");
    puts("    <Category name=\"logAll\" description=\"Everything, including debug messages\"/>");
    puts("  </LogCategories>");
    char stop[40], tolerance[40], step[40];
    printf("  <DefaultExperiment startTime=\"0\" stopTime=\"%s\" tolerance=\"%s\" stepSize=\"%s\"/>\n",
           real_text(MD.default_stop_time, stop, sizeof stop),
           real_text(MD.default_tolerance, tolerance, sizeof tolerance), real_text(h, step, sizeof step));
    puts("  <ModelVariables>");
    size_t index = 0;
    for (size_t v = 0; v < MD.n_variables; ++v)
        for (size_t e = 0; e < model_variable_count(&MD.variables[v]); ++e)
            print_variable(&MD.variables[v], e), ++index;
    puts("  </ModelVariables>");

    /* Outputs, then every output and calculated parameter as an initial unknown. */
    puts("  <ModelStructure>");
    for (int pass = 0; pass < 2; ++pass) {
        puts(pass == 0 ? "    <Outputs>" : "    <InitialUnknowns>");
        index = 0;
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
    return 0;
}
