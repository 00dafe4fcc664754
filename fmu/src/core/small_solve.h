/* Small linear systems (at most TP_MAX_COORDINATES unknowns): the accelerations of
 * a model file's equations, M q'' = b.  Plain C, no allocation. */
#ifndef SMALL_SOLVE_H
#define SMALL_SOLVE_H

#include "term_program.h"

/* Solves M x = b (n x n, rows of TP_MAX_COORDINATES) by Gaussian elimination with
 * partial pivoting; M and b are overwritten.  Returns 0, or -1 when a pivot is not
 * above `smallest_pivot` or a solution is not finite. */
int small_solve(int n, double M[][TP_MAX_COORDINATES], double b[], double x[],
                double smallest_pivot);

#endif
