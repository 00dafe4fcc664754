/* The check and the case table shared by the C test programs of the core:
 * every check prints one line, PASS or FAIL followed by what it measured and
 * the bound it was held to; `run_cases` runs the case named on the command
 * line (exit 0 if every check passed, 1 if one failed, 2 for an unknown case)
 * or, without an argument, lists the cases (CMake and tests/fmu/test_core.py
 * read the same table from the source). */
#ifndef CHECK_H
#define CHECK_H

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static inline int check(int ok, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    printf("%s ", ok ? "PASS" : "FAIL");
    vprintf(format, args);
    putchar('\n');
    va_end(args);
    return ok ? 0 : 1;
}

typedef struct {
    const char *name;
    int (*run)(void);
} TestCase;

static inline int run_cases(const char *program, const TestCase cases[], size_t n_cases, int argc,
                            char **argv)
{
    if (argc < 2) {
        for (size_t i = 0; i < n_cases; ++i) puts(cases[i].name);
        return 0;
    }
    for (size_t i = 0; i < n_cases; ++i)
        if (strcmp(argv[1], cases[i].name) == 0) return cases[i].run() ? 1 : 0;
    fprintf(stderr, "%s: unknown case %s\n", program, argv[1]);
    return 2;
}

#endif
