/* Observer gains from Theorem 3.1, condition (6), of Davila, Fridman and
 * Poznyak (2006):
 *     alpha1 > f+,   alpha2 > sqrt(2 / (alpha1 - f+)) (alpha1 + f+)(1 + p)/(1 - p)
 * where f+ bounds |f~ + xi| of (5) and 0 < p < 1. */
#ifndef GAINS_H
#define GAINS_H

/* alpha1 chosen when only f+ is given: twice the bound (a margin of f+). */
#define GAINS_ALPHA1_FACTOR 2.0
/* alpha2 chosen when not given: 10 % above the bound of (6). */
#define GAINS_ALPHA2_MARGIN 1.1

/* Right-hand side of (6) for alpha2; +infinity if alpha1 <= f+. */
double gains_alpha2_bound(double alpha1, double f_plus, double p);

/* Fills in a gain given as 0 from f+ and p by the rule above.  Returns 0 on
 * success, -1 if a gain is 0 and f+ is 0 too (nothing to compute it from). */
int gains_complete(double f_plus, double p, double *alpha1, double *alpha2);

#endif
