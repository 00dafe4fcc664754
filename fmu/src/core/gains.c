#include "gains.h"

#include <math.h>

double gains_alpha2_bound(double alpha1, double f_plus, double p)
{
    if (!(alpha1 > f_plus)) return INFINITY;
    return sqrt(2.0 / (alpha1 - f_plus)) * (alpha1 + f_plus) * (1.0 + p) / (1.0 - p);
}

int gains_complete(double f_plus, double p, double *alpha1, double *alpha2)
{
    if ((*alpha1 == 0.0 || *alpha2 == 0.0) && !(f_plus > 0.0)) return -1;
    if (*alpha1 == 0.0) *alpha1 = GAINS_ALPHA1_FACTOR * f_plus;
    if (*alpha2 == 0.0) {
        double bound = gains_alpha2_bound(*alpha1, f_plus, p);
        if (!isfinite(bound)) return -1;
        *alpha2 = GAINS_ALPHA2_MARGIN * bound;
    }
    return 0;
}
