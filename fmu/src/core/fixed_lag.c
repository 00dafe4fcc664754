#include "fixed_lag.h"
#include "fixed_lag_kernels.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846

/* The kernel K(t) = sin(a t) / (pi t) w(t) with a Blackman window w of half-width
 * T, at t (in samples). */
static double kernel(double a, double T, double t)
{
    const double s = fabs(t) < 1e-12 ? a / PI : sin(a * t) / (PI * t), b = PI / T;
    return s * (0.42 + 0.5 * cos(b * t) + 0.08 * cos(2.0 * b * t));
}

/* A smoothing kernel k0 of cut-off `fraction` (of the sample rate) over j = -half ..
 * half: K at the integers, normalized to sum 1. */
static void smoothing(double fraction, int half, double k0[])
{
    double sum = 0.0;
    for (int j = 0; j <= half; ++j) {
        k0[j] = kernel(2.0 * PI * fraction, half + 1.0, (double)j);
        sum += (j ? 2.0 : 1.0) * k0[j];
    }
    for (int j = 0; j <= half; ++j) k0[j] /= sum;
}

/* Candidate c's velocity and acceleration kernels at step h (fixed_lag_kernels.h:
 * their responses are i w and -w^2 times k0's over its band, exact on constants, ramps
 * and parabolas); returns the acceleration's variance per unit white noise variance. */
static double derivatives(int c, int half, double h, double k1[], double k2[])
{
    const double *v = FL_KERNEL_VELOCITY + FL_KERNEL_OFFSET[c],
                 *a = FL_KERNEL_ACCELERATION + FL_KERNEL_OFFSET[c];
    double noise = 0.0;
    for (int j = 0; j <= half; ++j) {
        k1[j] = v[j] / h;
        k2[j] = a[j] / (h * h);
        noise += (j ? 2.0 : 1.0) * k2[j] * k2[j];
    }
    return noise;
}

_Static_assert(FL_CANDIDATES >= 1 && FL_CANDIDATES <= 8, "candidates halve the band");
_Static_assert(FL_KERNEL_CANDIDATES == FL_CANDIDATES, "fixed_lag_kernels.h is of these "
               "candidates: python -m tools.fixed_lag_kernels");

/* The held input's kernel of cut-off `fraction`: K at m + 1/2, normalized to sum 1
 * over the 2 (half + 1) samples it weighs. */
static void held_kernel(double fraction, int half, double held[])
{
    double sum = 0.0;
    for (int m = 0; m <= half; ++m) {
        held[m] = kernel(2.0 * PI * fraction, half + 1.0, m + 0.5);
        sum += 2.0 * held[m];
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
        f->lead[c] = (int)fmin(ceil(FL_REVERSAL_PERIODS / fraction - 1e-9), FL_MAX_LEAD);
        smoothing(fraction, f->half[c], f->k0[c]);
        f->noise_gain[c] = derivatives(c, f->half[c], h, f->k1[c], f->k2[c]);
        held_kernel(fraction, f->half[c], f->held[c]);
    }
    smoothing(FL_PROBE_FRACTION, FL_PROBE_HALF, f->probe);
    f->probe_gain = (1.0 - f->probe[0]) * (1.0 - f->probe[0]); /* sum (delta_j - k0_j)^2 */
    for (int j = 1; j <= FL_PROBE_HALF; ++j) f->probe_gain += 2.0 * f->probe[j] * f->probe[j];
    return 0;
}

/* Signal s's sample `lag` samples behind the newest; its neighbours are at +-j. */
static const double *behind(const FixedLag *f, int lag, int s)
{
    return &f->ring[s][f->newest + FL_RING - lag];
}

/* The window w[-half .. half] through the even kernel k (k0, k2). */
static double even(const double *w, int half, const double k[])
{
    double sum = k[0] * w[0];
    for (int j = 1; j <= half; ++j) sum += k[j] * (w[j] + w[-j]);
    return sum;
}

/* The chosen candidate's centre: half samples behind the newest, and the lead further. */
static int lag(const FixedLag *f)
{
    return f->half[f->chosen] + (f->leads ? f->lead[f->chosen] : 0);
}

int fl_add_term(FixedLag *f, int held, int tag)
{
    if (f->terms >= FL_MAX_TERMS) return -1;
    f->term_held[f->terms] = held != 0;
    f->term_tag[f->terms] = tag;
    return f->terms++;
}

void fl_lead(FixedLag *f) { f->leads = 1; }

void fl_push(FixedLag *f, const double y[], const double u[], const double terms[])
{
    f->newest = f->newest + 1 < FL_RING ? f->newest + 1 : 0;
    for (int s = 0; s < f->signals + f->terms; ++s)
        f->ring[s][f->newest] = f->ring[s][f->newest + FL_RING] =
            s < f->coordinates ? y[s] : s < f->signals ? u[s - f->coordinates]
                                                       : terms[s - f->signals];
    if (f->filled < FL_RING) ++f->filled;
    if (f->chosen >= 0) return; /* the choice is made: no more statistics needed */
    if (f->filled >= 2 * FL_PROBE_HALF + 1) {
        for (int i = 0; i < f->coordinates; ++i) {
            const double *w = behind(f, FL_PROBE_HALF, i);
            const double r = w[0] - even(w, FL_PROBE_HALF, f->probe);
            f->noise_square[i] += r * r;
        }
        f->noise_squares += 1.0;
    }
    for (int c = 0; c < FL_CANDIDATES; ++c) {
        if (f->filled < 2 * f->half[c] + 1) break; /* the next ones are longer */
        for (int i = 0; i < f->coordinates; ++i) {
            const double a = even(behind(f, f->half[c], i), f->half[c], f->k2[c]);
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
    return f->chosen >= 0 && f->filled >= f->half[f->chosen] + lag(f) + 1 + f->inputs_held;
}

/* Signal s smoothed as an input: sampled (k0) or held over each sample. */
static double as_input(const FixedLag *f, int s, int held)
{
    const int c = f->chosen, half = f->half[c];
    const double *w = behind(f, lag(f), s), *kernel = f->held[c];
    if (!held) return even(w, half, f->k0[c]);
    double sum = 0.0;
    for (int m = 0; m <= half; ++m) sum += kernel[m] * (w[m] + w[-m - 1]);
    return sum;
}

void fl_at_lag(const FixedLag *f, double q[], double qd[], double qdd[], double u[],
               double terms[])
{
    const int c = f->chosen, half = f->half[c];
    const double *k0 = f->k0[c], *k1 = f->k1[c], *k2 = f->k2[c];
    for (int i = 0; i < f->coordinates; ++i) { /* the three kernels in one pass */
        const double *w = behind(f, lag(f), i);
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
    for (int s = f->coordinates; s < f->signals; ++s)
        u[s - f->coordinates] = as_input(f, s, f->inputs_held);
    for (int k = 0; k < f->terms; ++k) terms[k] = as_input(f, f->signals + k, f->term_held[k]);
}

double fl_lead_velocity(const FixedLag *f, int i)
{
    const int c = f->chosen, half = f->half[c];
    const double *w = behind(f, half, i), *k1 = f->k1[c];
    double velocity = 0.0;
    for (int j = 1; j <= half; ++j) velocity += k1[j] * (w[j] - w[-j]);
    return velocity;
}

int fl_lead_samples(const FixedLag *f)
{
    return f->chosen >= 0 && f->leads ? f->lead[f->chosen] : 0;
}

double fl_cutoff(const FixedLag *f)
{
    return f->chosen >= 0 ? FL_HIGHEST_FRACTION / f->h / (double)(1 << f->chosen) : 0.0;
}
