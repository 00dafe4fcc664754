/* The harness's native co-simulation loop: drives FMUs that fmpy has
 * instantiated, through their FMI 2 function pointers, so that the per-step
 * coupling costs no Python.  harness/master.py holds the plain-Python twin of
 * this loop; both must produce identical records.
 *
 * One macro step k (time t = t0 + k*H), for each FMU in step order:
 *   for each link into it: value = source output (or signal[k]) + noise[k]; set it
 *   fmi2DoStep(t, H)
 * then, every `decimation` steps, the probes are read into the next record row: one
 * fmi2GetReal for each run of consecutive probes of one FMU (the 20 outputs of identify's
 * observer a sample: one call each was half the loop's time). */
#include <stddef.h>

typedef int (*DoStepFn)(void *, double, double, int);
typedef int (*GetRealFn)(void *, const unsigned *, size_t, double *);
typedef int (*SetRealFn)(void *, const unsigned *, size_t, const double *);

typedef struct {
    void *component;
    DoStepFn do_step;
    GetRealFn get_real;
    SetRealFn set_real;
} LoopFMU;

typedef struct {
    int source_fmu;     /* -1: the source is signal `source_signal` */
    unsigned source_vr;
    int source_signal;
    int noise_signal;   /* -1: none; else added to the value */
    int target_fmu;
    unsigned target_vr;
} LoopLink;

typedef struct {
    int fmu;
    unsigned vr;
} LoopProbe;

/* Where a run stopped: step index, FMU, and the FMI call (0 doStep, 1 get, 2 set). */
typedef struct {
    long step;
    int fmu;
    int call;
    int status;
} LoopFailure;

#define FMI2_ERROR 3
#define PROBE_BATCH 64 /* probes read by one fmi2GetReal at most */

/* The value a link delivers at step k; returns the FMI status of the read. */
static int link_value(const LoopFMU *fmus, const LoopLink *link, const double *signals,
                      long signal_stride, long k, double *value)
{
    int status = 0;
    if (link->source_fmu < 0) {
        *value = signals[(long)link->source_signal * signal_stride + k];
    } else {
        const LoopFMU *src = &fmus[link->source_fmu];
        status = src->get_real(src->component, &link->source_vr, 1, value);
    }
    if (link->noise_signal >= 0) *value += signals[(long)link->noise_signal * signal_stride + k];
    return status;
}

/* Runs steps k_begin..k_end-1; returns the number of record rows written, or -1
 * with *failure filled in. */
long loop_run(const LoopFMU *fmus, const int *order, int n_order, const LoopLink *links,
              int n_links, const double *signals, long signal_stride, const LoopProbe *probes,
              int n_probes, long decimation, double *records, double t0, double H, long k_begin,
              long k_end, LoopFailure *failure)
{
    long rows = 0;
    for (long k = k_begin; k < k_end; ++k) {
        const double t = t0 + (double)k * H;
        for (int o = 0; o < n_order; ++o) {
            const int f = order[o];
            const LoopFMU *dst = &fmus[f];
            for (int l = 0; l < n_links; ++l) {
                const LoopLink *link = &links[l];
                if (link->target_fmu != f) continue;
                double value;
                int status = link_value(fmus, link, signals, signal_stride, k, &value);
                if (status >= FMI2_ERROR) {
                    *failure = (LoopFailure){k, link->source_fmu, 1, status};
                    return -1;
                }
                status = dst->set_real(dst->component, &link->target_vr, 1, &value);
                if (status >= FMI2_ERROR) {
                    *failure = (LoopFailure){k, f, 2, status};
                    return -1;
                }
            }
            const int status = dst->do_step(dst->component, t, H, 0);
            if (status >= FMI2_ERROR) {
                *failure = (LoopFailure){k, f, 0, status};
                return -1;
            }
        }
        if ((k + 1) % decimation == 0) {
            double *row = records + rows * (long)(n_probes + 1);
            row[0] = t0 + (double)(k + 1) * H;
            for (int p = 0; p < n_probes;) {
                const int fmu = probes[p].fmu;
                unsigned vrs[PROBE_BATCH];
                int n = 0;
                for (; p + n < n_probes && n < PROBE_BATCH && probes[p + n].fmu == fmu; ++n)
                    vrs[n] = probes[p + n].vr;
                const LoopFMU *src = &fmus[fmu];
                const int status = src->get_real(src->component, vrs, (size_t)n, &row[p + 1]);
                if (status >= FMI2_ERROR) {
                    *failure = (LoopFailure){k, fmu, 1, status};
                    return -1;
                }
                p += n;
            }
            ++rows;
        }
    }
    return rows;
}
