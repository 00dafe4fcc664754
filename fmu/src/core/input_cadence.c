/* The cadence of an FMU's inputs (input_cadence.h). */
#include "input_cadence.h"

#include <math.h>
#include <string.h>

#include "tuning.h"

/* since_change is capped here: a hold longer than this is only "long" */
#define IC_LONGEST 1000000000

void ic_init(InputCadence *c, int count, const double values[], double h, double period)
{
    memset(c, 0, sizeof *c);
    c->count = count < 0 ? 0 : (count > IC_MAX_VALUES ? IC_MAX_VALUES : count);
    const double steps = floor(CADENCE_WINDOW / h + 0.5);
    c->window = steps < 1.0 ? 1 : (steps > IC_LONGEST ? IC_LONGEST : (int)steps);
    const double expected = period > 0.0 ? floor(period / h + 0.5) : 1.0;
    c->expected = expected < 1.0 ? 1 : (expected > IC_LONGEST ? IC_LONGEST : (int)expected);
    memcpy(c->last, values, (size_t)c->count * sizeof c->last[0]);
}

void ic_advance(InputCadence *c, const double values[], unsigned long long steps)
{
    if (steps == 0) return;
    /* compared bit for bit: a change is any new sample, NaN or signed zero included */
    if (memcmp(values, c->last, (size_t)c->count * sizeof c->last[0]) != 0) {
        if (c->since_change > 0 &&
            (c->window_shortest == 0 || c->since_change < c->window_shortest))
            c->window_shortest = c->since_change;
        c->since_change = 0;
        if (c->window_changes < 2) c->window_changes += 1;
        memcpy(c->last, values, (size_t)c->count * sizeof c->last[0]);
    }
    const unsigned long long held = (unsigned long long)c->since_change + steps;
    c->since_change = held > IC_LONGEST ? IC_LONGEST : (int)held;
    const unsigned long long age = (unsigned long long)c->window_age + steps;
    if (age < (unsigned long long)c->window) {
        c->window_age = (int)age;
        return;
    }
    /* the window completes within these steps (whole windows after it saw no change:
     * they leave the verdict) */
    const unsigned long long after = age - (unsigned long long)c->window;
    if (c->window_changes >= 2) c->shortest = c->window_shortest;
    c->window_shortest = 0;
    c->window_changes = 0;
    c->window_age = (int)(after % (unsigned long long)c->window);
}

int ic_shortest(const InputCadence *c) { return c->shortest; }

int ic_coarse(const InputCadence *c)
{
    return c->shortest > c->expected && c->shortest >= CADENCE_COARSE_STEPS;
}

int ic_valid(const InputCadence *c) { return c->window_age >= 0 && c->window_age < c->window; }
