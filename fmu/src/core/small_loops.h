/* Helpers for the per-step kernels, whose loops run over the active number
 * of regressors m (1..ID_MAX_REGRESSORS = 8).  With m a run-time value the
 * loop control costs as much as the arithmetic of a 3-regressor step; a
 * kernel instantiated for each constant m, with its loops unrolled, has none.
 * Compilers without an unrolling pragma just keep the loops. */
#ifndef SMALL_LOOPS_H
#define SMALL_LOOPS_H

#if defined(__clang__)
#define UNROLL _Pragma("clang loop unroll(full)")
#elif defined(__GNUC__)
#define UNROLL _Pragma("GCC unroll 8")
#else
#define UNROLL
#endif

/* A kernel must be inlined into its constant-m call for the loops to unroll. */
#if defined(__GNUC__)
#define INLINED static inline __attribute__((always_inline))
#else
#define INLINED static inline
#endif
#define KERNEL INLINED void

/* Calls FUNCTION(args..., M) with the constant M equal to m; does nothing for
 * m outside 1..8 (the callers' counts are validated, this is the last guard). */
#define WITH_CONSTANT_M(m, FUNCTION, ...)            \
    do {                                              \
        switch (m) {                                  \
        case 1: FUNCTION(__VA_ARGS__, 1); break;      \
        case 2: FUNCTION(__VA_ARGS__, 2); break;      \
        case 3: FUNCTION(__VA_ARGS__, 3); break;      \
        case 4: FUNCTION(__VA_ARGS__, 4); break;      \
        case 5: FUNCTION(__VA_ARGS__, 5); break;      \
        case 6: FUNCTION(__VA_ARGS__, 6); break;      \
        case 7: FUNCTION(__VA_ARGS__, 7); break;      \
        case 8: FUNCTION(__VA_ARGS__, 8); break;      \
        default: break;                               \
        }                                             \
    } while (0)

/* FUNCTION(args..., ROWS, M): the same, with the number of rows of the
 * regression (the DOFs) a constant too when it is 1, the built-in joint's
 * case, so that the loops over rows go as well. */
#define WITH_CONSTANT_SIZES(rows, m, FUNCTION, ...)                        \
    do {                                                                    \
        if ((rows) == 1) WITH_CONSTANT_M(m, FUNCTION, __VA_ARGS__, 1);     \
        else WITH_CONSTANT_M(m, FUNCTION, __VA_ARGS__, (rows));            \
    } while (0)

#endif
