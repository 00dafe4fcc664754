/* Random data and their comparison, shared by the C tests of the regressor
 * identifier and of its statistics job (test_regressor_identifier.c,
 * test_statistics_job.c): a fixed-seed generator, so that every platform sees the
 * same samples, and the relative difference of two results. */
#ifndef RANDOM_DATA_H
#define RANDOM_DATA_H

#include <math.h>

static inline double uniform_random(unsigned long *state) /* in [-1, 1) */
{
    *state = *state * 6364136223846793005UL + 1442695040888963407UL;
    return (double)(*state >> 11) / 4503599627370496.0 - 1.0;
}

static inline double relative(double a, double b)
{
    const double scale = fmax(fabs(a), fabs(b));
    return scale > 0.0 ? fabs(a - b) / scale : 0.0;
}

#endif
