/* Small linear systems (small_solve.h). */
#include "small_solve.h"

#include <math.h>

int small_solve(int n, double M[][TP_MAX_COORDINATES], double b[], double x[],
                double smallest_pivot)
{
    for (int c = 0; c < n; ++c) {
        int pivot = c;
        for (int r = c + 1; r < n; ++r)
            if (fabs(M[r][c]) > fabs(M[pivot][c])) pivot = r;
        if (!(fabs(M[pivot][c]) > smallest_pivot)) return -1;
        if (pivot != c) {
            for (int j = 0; j < n; ++j) {
                const double t = M[c][j];
                M[c][j] = M[pivot][j];
                M[pivot][j] = t;
            }
            const double t = b[c];
            b[c] = b[pivot];
            b[pivot] = t;
        }
        for (int r = c + 1; r < n; ++r) {
            const double f = M[r][c] / M[c][c];
            for (int j = c; j < n; ++j) M[r][j] -= f * M[c][j];
            b[r] -= f * b[c];
        }
    }
    for (int c = n - 1; c >= 0; --c) {
        double v = b[c];
        for (int j = c + 1; j < n; ++j) v -= M[c][j] * x[j];
        x[c] = v / M[c][c];
        if (!isfinite(x[c])) return -1;
    }
    return 0;
}
