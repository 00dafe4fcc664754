/* Unit tests of the fixed-lag derivatives (fmu/src/core/fixed_lag.h): run as
 * `test_fixed_lag CASE` (check.h). */
#include <math.h>
#include <stdint.h>

#include "check.h"

#include "fixed_lag.h"

#define H 1e-3
#define PI 3.14159265358979323846

static FixedLag window; /* 60 kB: not on the stack */

/* A parabola's velocity and acceleration and a ramp input come out exact at the lag,
 * whatever the candidate; its value within 1e-5 (a low-pass smooths a curvature by the
 * kernel's second moment, which the windowed sinc keeps small). */
static int polynomials_are_exact(void)
{
    int failed = 0;
    for (int c = 0; c < FL_CANDIDATES; ++c) {
        fl_init(&window, 1, 1, 0, H);
        const int samples = 2 * window.half[c] + 1 + 17;
        for (int k = 0; k < samples; ++k) {
            const double t = k * H, y = 1.0 + 2.0 * t - 3.0 * t * t, u = 5.0 * t;
            fl_push(&window, &y, &u, NULL);
        }
        window.chosen = c;
        double q, qd, qdd, u;
        fl_at_lag(&window, &q, &qd, &qdd, &u, NULL);
        const double t = (samples - 1 - window.half[c]) * H;
        const double exact = fmax(fmax(fabs(qd - (2.0 - 6.0 * t)) / 2.0, fabs(qdd + 6.0) / 6.0),
                                  fabs(u - 5.0 * t));
        const double value = fabs(q - (1.0 + 2.0 * t - 3.0 * t * t));
        failed += check(exact < 1e-9 && value < 1e-5, "candidate %d (half %d): a parabola's "
                        "velocity and acceleration and a ramp input at the lag, worst error "
                        "%.2e (expected < 1e-9); the parabola's value %.2e (expected < 1e-5)",
                        c, window.half[c], exact, value);
    }
    return failed;
}

/* A sine well inside the band: its derivatives within 0.5 %, at the centre. */
static int a_sine_in_the_band_keeps_its_derivatives(void)
{
    fl_init(&window, 1, 0, 0, H);
    const double w = 2.0 * PI * 30.0; /* 30 Hz against the widest band's 200 Hz */
    int k = 0;
    for (; k < 200; ++k) {
        const double y = sin(w * k * H);
        fl_push(&window, &y, NULL, NULL);
    }
    window.chosen = 0;
    double q, qd, qdd;
    fl_at_lag(&window, &q, &qd, &qdd, NULL, NULL);
    const double t = (k - 1 - window.half[0]) * H;
    const double error = fmax(fabs(qd - w * cos(w * t)) / w, fabs(qdd + w * w * sin(w * t)) / (w * w));
    return check(error < 5e-3, "30 Hz sine through the 200 Hz window: velocity and "
                 "acceleration within %.2e of their amplitudes (expected < 5e-3)", error);
}

/* The smoothed equation of a pure sinusoid, m y'' + d y' + k y = u with u sampled
 * alike, holds to 1e-6 of its terms in every candidate's band: at w h = 0.7 with the
 * widest (the oscillator's resonance at 610 Hz), and at the same share of each
 * narrower band; the velocity is w times the smoothed cosine to 1e-6.  Sampling K''
 * and normalizing it on a parabola made the acceleration kernel's gain 1 + 6.8e-3
 * there. */
static int a_sinusoid_keeps_its_equation(void)
{
    int failed = 0;
    const double h = 1.0 / 610.0, m = 1.0, d = 25.6, k = 1.826e5;
    for (int c = 0; c < FL_CANDIDATES; ++c)
        for (int phase = 0; phase < 3; ++phase) {
            const double w = 0.7 / (double)(1 << c) / h, shift = 0.4 * phase;
            fl_init(&window, 1, 2, 0, h);
            for (int n = 0; n < 2 * window.half[c] + 1 + 5 * phase; ++n) {
                const double t = n * h, y = sin(w * t + shift), cosine = cos(w * t + shift);
                const double u[2] = {(k - m * w * w) * y + d * w * cosine, cosine};
                fl_push(&window, &y, u, NULL);
            }
            window.chosen = c;
            double q, qd, qdd, u[2];
            fl_at_lag(&window, &q, &qd, &qdd, u, NULL);
            const double residual = fabs(m * qdd + d * qd + k * q - u[0]) / k;
            const double velocity = fabs(qd - w * u[1]) / w;
            failed += check(residual < 1e-6 && velocity < 1e-6, "candidate %d, w h = %g, phase "
                            "%g: the smoothed equation's residual %.2e of k y's amplitude, the "
                            "velocity's error %.2e of its amplitude (expected < 1e-6)", c, w * h,
                            shift, residual, velocity);
        }
    return failed;
}

/* A cubic stiffness, m y'' + k y + k3 y^3 = u: with y^3 a term (the samples cubed,
 * then smoothed as u is) the smoothed equation holds to 1e-6 of k y at w h = 0.7,
 * where the cube of the smoothed y misses it by the part of y^3 beyond the band (its
 * third harmonic at 2.1, past the cut-off 1.26). */
static int a_term_passes_the_window_as_the_equation(void)
{
    const double h = 1.0 / 610.0, m = 1.0, k = 1.826e5, k3 = 6.5e6, w = 0.7 / h, A = 0.07;
    fl_init(&window, 1, 1, 0, h);
    int failed = check(fl_add_term(&window, 0, 17) == 0, "the first term is term 0");
    for (int n = 0; n < 2 * window.half[0] + 1; ++n) {
        const double y = A * sin(w * n * h + 0.3), cube = y * y * y;
        const double u = (k - m * w * w) * y + k3 * cube;
        fl_push(&window, &y, &u, &cube);
    }
    window.chosen = 0;
    double q, qd, qdd, u, cube;
    fl_at_lag(&window, &q, &qd, &qdd, &u, &cube);
    const double term = fabs(m * qdd + k * q + k3 * cube - u) / (k * A);
    const double smoothed = fabs(m * qdd + k * q + k3 * q * q * q - u) / (k * A);
    failed += check(term < 1e-6 && smoothed > 1e-3 && window.term_tag[0] == 17, "the "
                    "smoothed equation's residual with the term %.2e of k y (expected < "
                    "1e-6), with the smoothed y cubed %.2e (expected > 1e-3)", term, smoothed);
    for (int t = 1; t < FL_MAX_TERMS; ++t) fl_add_term(&window, 0, t);
    failed += check(fl_add_term(&window, 0, 0) == -1, "no term past FL_MAX_TERMS");
    return failed;
}

/* Reproducible white noise in [-sqrt 3, sqrt 3]: unit variance. */
static double noise(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return ((double)(*state >> 11) / 9007199254740992.0 - 0.5) * 2.0 * sqrt(3.0);
}

/* The probe measures white noise on a slow motion within 10 %, and the choice
 * narrows the band as the noise grows. */
static int the_band_follows_the_noise(void)
{
    int failed = 0, previous = -1;
    const double levels[] = {0.0, 1e-7, 1e-5, 1e-3};
    for (size_t n = 0; n < sizeof levels / sizeof levels[0]; ++n) {
        uint64_t state = 7;
        fl_init(&window, 1, 0, 0, H);
        for (int k = 0; k < 4000; ++k) {
            const double t = k * H;
            const double y = 0.1 * sin(2.0 * PI * 2.0 * t) + levels[n] * noise(&state);
            fl_push(&window, &y, NULL, NULL);
        }
        const double measured = fl_noise_std(&window, 0);
        const int chosen = fl_choose(&window);
        if (levels[n] > 0.0)
            failed += check(fabs(measured / levels[n] - 1.0) < 0.1, "noise %g: the probe "
                            "measures %g (expected within 10 %%)", levels[n], measured);
        failed += check(chosen >= previous, "noise %g: candidate %d (cut-off %g Hz), no wider "
                        "than at less noise (%d)", levels[n], chosen, fl_cutoff(&window),
                        previous);
        previous = chosen;
    }
    failed += check(previous == FL_CANDIDATES - 1, "the loudest noise takes the narrowest "
                    "band: candidate %d (expected %d)", previous, FL_CANDIDATES - 1);
    return failed;
}

/* An input held over each sample is the staircase it draws: a held ramp's samples
 * smooth to the ramp half a sample earlier, where sampled they give the ramp. */
static int a_held_input_is_a_staircase(void)
{
    int failed = 0;
    for (int held = 0; held <= 1; ++held) {
        fl_init(&window, 1, 1, held, H);
        const int samples = 2 * window.half[1] + 2 + 9;
        for (int k = 0; k < samples; ++k) {
            const double y = 0.0, u = 3.0 * k * H;
            fl_push(&window, &y, &u, NULL);
        }
        window.chosen = 1;
        double q, qd, qdd, u;
        fl_at_lag(&window, &q, &qd, &qdd, &u, NULL);
        const double t = (samples - 1 - window.half[1]) * H;
        const double expected = 3.0 * (t - (held ? 0.5 * H : 0.0));
        failed += check(fl_ready(&window) && fabs(u - expected) < 1e-12, "inputs held %d: the "
                        "ramp 3 t smoothed at t = %g: %.15g (expected %.15g)", held, t, u,
                        expected);
    }
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"polynomials_are_exact", polynomials_are_exact},
        {"a_sine_in_the_band_keeps_its_derivatives", a_sine_in_the_band_keeps_its_derivatives},
        {"a_sinusoid_keeps_its_equation", a_sinusoid_keeps_its_equation},
        {"a_term_passes_the_window_as_the_equation", a_term_passes_the_window_as_the_equation},
        {"the_band_follows_the_noise", the_band_follows_the_noise},
        {"a_held_input_is_a_staircase", a_held_input_is_a_staircase},
    };
    return run_cases("test_fixed_lag", cases, sizeof cases / sizeof cases[0], argc, argv);
}
