#include "fixed_lag.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846

/* The kernel K(t) = sin(a t) / (pi t) w(t) with a Blackman window w of half-width
 * T, and its first two derivatives, at t (in samples). */
static void kernel(double a, double T, double t, double out[3])
{
    double s, s1, s2;
    if (fabs(t) < 1e-12) {
        s = a / PI;
        s1 = 0.0;
        s2 = -a * a * a / (3.0 * PI);
    } else {
        const double sn = sin(a * t), cs = cos(a * t);
        s = sn / (PI * t);
        s1 = (a * t * cs - sn) / (PI * t * t);
        s2 = (-a * a * t * t * sn - 2.0 * a * t * cs + 2.0 * sn) / (PI * t * t * t);
    }
    const double b = PI / T;
    const double w = 0.42 + 0.5 * cos(b * t) + 0.08 * cos(2.0 * b * t);
    const double w1 = -0.5 * b * sin(b * t) - 0.16 * b * sin(2.0 * b * t);
    const double w2 = -0.5 * b * b * cos(b * t) - 0.32 * b * b * cos(2.0 * b * t);
    out[0] = s * w;
    out[1] = s1 * w + s * w1;
    out[2] = s2 * w + 2.0 * s1 * w1 + s * w2;
}

/* A smoothing kernel k0 of cut-off `fraction` (of the sample rate) over j = -half ..
 * half, and its derivatives k1, k2 (model_pipeline.h), normalized on constants, ramps
 * and parabolas; returns the acceleration's variance per unit white noise variance. */
static double coefficients(double fraction, int half, double h, double k0[], double k1[],
                           double k2[])
{
    double sum0 = 0.0, sum2 = 0.0;
    for (int j = 0; j <= half; ++j) {
        double K[3];
        kernel(2.0 * PI * fraction, half + 1.0, (double)j, K);
        k0[j] = K[0];
        k1[j] = -K[1]; /* q^'(centre) = sum y_j K'(-j) and K' is odd */
        k2[j] = K[2];
        const double twice = j ? 2.0 : 1.0; /* j and -j */
        sum0 += twice * k0[j];
        sum2 += twice * k2[j];
    }
    for (int j = 0; j <= half; ++j) {
        k0[j] /= sum0;
        k2[j] -= sum2 * k0[j]; /* no response to a constant */
    }
    double ramp = 0.0, parabola = 0.0, noise = 0.0;
    for (int j = 1; j <= half; ++j) {
        ramp += 2.0 * k1[j] * j;
        parabola += k2[j] * (double)j * j; /* 2 k2[j] j^2 / 2 */
    }
    for (int j = 0; j <= half; ++j) {
        k1[j] /= ramp * h;
        k2[j] /= parabola * h * h;
        noise += (j ? 2.0 : 1.0) * k2[j] * k2[j];
    }
    return noise;
}

_Static_assert(FL_CANDIDATES >= 1 && FL_CANDIDATES <= 8, "candidates halve the band");

/* The held input's kernel of cut-off `fraction`: K at m + 1/2, normalized to sum 1
 * over the 2 (half + 1) samples it weighs. */
static void held_kernel(double fraction, int half, double held[])
{
    double sum = 0.0;
    for (int m = 0; m <= half; ++m) {
        double K[3];
        kernel(2.0 * PI * fraction, half + 1.0, m + 0.5, K);
        held[m] = K[0];
        sum += 2.0 * K[0];
    }
    for (int m = 0; m <= half; ++m) held[m] /= sum;
}

int fl_init(FixedLag *f, int coordinates, int inputs, int inputs_held, double h)
{
    if (coordinates < 0 || inputs < 0 || coordinates + inputs > FL_MAX_SIGNALS ||
        !(h > 0.0) || !isfinite(h))
        return -1;
    memset(f, 0, sizeof *f);
    f->coordinates = coordinates;
    f->signals = coordinates + inputs;
    f->h = h;
    f->inputs_held = inputs_held != 0;
    f->chosen = -1;
    double fraction = FL_HIGHEST_FRACTION;
    for (int c = 0; c < FL_CANDIDATES; ++c, fraction *= 0.5) {
        f->half[c] = (int)fmin(ceil(FL_CYCLES / fraction - 1e-9), FL_MAX_HALF);
        f->noise_gain[c] = coefficients(fraction, f->half[c], h, f->k0[c], f->k1[c], f->k2[c]);
        held_kernel(fraction, f->half[c], f->held[c]);
    }
    double d1[FL_PROBE_HALF + 1], d2[FL_PROBE_HALF + 1];
    coefficients(FL_PROBE_FRACTION, FL_PROBE_HALF, h, f->probe, d1, d2);
    f->probe_gain = (1.0 - f->probe[0]) * (1.0 - f->probe[0]); /* sum (delta_j - k0_j)^2 */
    for (int j = 1; j <= FL_PROBE_HALF; ++j) f->probe_gain += 2.0 * f->probe[j] * f->probe[j];
    return 0;
}

/* Signal s's window of `half` on each side, centred `half` samples behind the
 * newest: w[-half .. half]. */
static const double *centre(const FixedLag *f, int half, int s)
{
    return &f->ring[s][f->newest + FL_RING - half];
}

/* Signal s through the even kernel k (k0, k2) of `half` on each side. */
static double even(const FixedLag *f, int half, const double k[], int s)
{
    const double *w = centre(f, half, s);
    double sum = k[0] * w[0];
    for (int j = 1; j <= half; ++j) sum += k[j] * (w[j] + w[-j]);
    return sum;
}

void fl_push(FixedLag *f, const double y[], const double u[])
{
    f->newest = f->newest + 1 < FL_RING ? f->newest + 1 : 0;
    for (int s = 0; s < f->signals; ++s)
        f->ring[s][f->newest] = f->ring[s][f->newest + FL_RING] =
            s < f->coordinates ? y[s] : u[s - f->coordinates];
    if (f->filled < FL_RING) ++f->filled;
    if (f->chosen >= 0) return; /* the choice is made: no more statistics needed */
    if (f->filled >= 2 * FL_PROBE_HALF + 1) {
        for (int i = 0; i < f->coordinates; ++i) {
            const double r = centre(f, FL_PROBE_HALF, i)[0] - even(f, FL_PROBE_HALF, f->probe, i);
            f->noise_square[i] += r * r;
        }
        f->noise_squares += 1.0;
    }
    for (int c = 0; c < FL_CANDIDATES; ++c) {
        if (f->filled < 2 * f->half[c] + 1) break; /* the next ones are longer */
        for (int i = 0; i < f->coordinates; ++i) {
            const double a = even(f, f->half[c], f->k2[c], i);
            f->square[c][i] += a * a;
        }
        f->squares[c] += 1.0;
    }
}

double fl_noise_std(const FixedLag *f, int i)
{
    return f->noise_squares > 0.0 ? sqrt(f->noise_square[i] / f->noise_squares / f->probe_gain)
                                  : 0.0;
}

int fl_choose(FixedLag *f)
{
    int chosen = FL_CANDIDATES - 1;
    for (int c = 0; c < FL_CANDIDATES && f->squares[c] > 0.0; ++c) {
        int quiet = 1;
        for (int i = 0; i < f->coordinates; ++i) {
            const double noise = fl_noise_std(f, i);
            if (noise * noise * f->noise_gain[c] > FL_NOISE_SHARE * f->square[c][i] / f->squares[c])
                quiet = 0;
        }
        if (quiet) {
            chosen = c;
            break;
        }
    }
    f->chosen = chosen;
    return chosen;
}

int fl_ready(const FixedLag *f)
{
    return f->chosen >= 0 && f->filled >= 2 * f->half[f->chosen] + 1 + f->inputs_held;
}

void fl_at_lag(const FixedLag *f, double q[], double qd[], double qdd[], double u[])
{
    const int c = f->chosen, half = f->half[c];
    const double *k0 = f->k0[c], *k1 = f->k1[c], *k2 = f->k2[c];
    for (int i = 0; i < f->coordinates; ++i) { /* the three kernels in one pass */
        const double *w = centre(f, half, i);
        double value = k0[0] * w[0], velocity = 0.0, acceleration = k2[0] * w[0];
        for (int j = 1; j <= half; ++j) {
            const double sum = w[j] + w[-j];
            value += k0[j] * sum;
            velocity += k1[j] * (w[j] - w[-j]);
            acceleration += k2[j] * sum;
        }
        q[i] = value;
        qd[i] = velocity;
        qdd[i] = acceleration;
    }
    for (int s = f->coordinates; s < f->signals; ++s) {
        if (!f->inputs_held) {
            u[s - f->coordinates] = even(f, half, k0, s);
            continue;
        }
        const double *w = centre(f, half, s), *held = f->held[c];
        double sum = 0.0;
        for (int m = 0; m <= half; ++m) sum += held[m] * (w[m] + w[-m - 1]);
        u[s - f->coordinates] = sum;
    }
}

double fl_cutoff(const FixedLag *f)
{
    return f->chosen >= 0 ? FL_HIGHEST_FRACTION / f->h / (double)(1 << f->chosen) : 0.0;
}
