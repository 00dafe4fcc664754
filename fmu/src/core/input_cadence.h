/* How often an FMU's measured inputs change, counted on its internal step.
 *
 * The observer and identifier assume one new sample per internal step h.  A
 * master whose communication step is N h (fmpy's default output interval, a
 * coarse co-simulation step) or an encoder coarser than the motion feeds them a
 * staircase that holds each value N steps: the velocities lag and the
 * identifier's regressors are biased, with nothing else to show it.  The
 * cadence is the shortest hold between two changes of any input, over a window
 * of CADENCE_WINDOW seconds in which they changed at least twice (so that one
 * hold lies inside it: holds up to half the window are seen); a window with
 * fewer changes (inputs at rest, motion starting) leaves the last verdict.
 * Every input held longer than expected over such a window is a staircase:
 * longer than one internal step, or than the period the importer states (an
 * internal step chosen finer than the log's sample period on purpose).
 *
 * Counted per internal step, a change at the first step of the interval it
 * enters (the importer sets inputs before a doStep): the same inputs give the
 * same cadence whatever the communication step.  Plain C, no allocation. */
#ifndef INPUT_CADENCE_H
#define INPUT_CADENCE_H

#define IC_MAX_VALUES 32

typedef struct {
    int count;                 /* values watched */
    int window;                /* internal steps per window */
    int expected;              /* internal steps a value is expected to hold, at most */
    double last[IC_MAX_VALUES]; /* the values of the last internal step */
    int since_change;          /* internal steps since they last changed (capped) */
    int window_age;            /* internal steps into the current window */
    int window_changes;        /* changes in the current window (counted up to 2) */
    int window_shortest;       /* shortest hold ended in the current window (0: none) */
    int shortest;              /* ... in the last complete window that changed twice (0: none) */
} InputCadence;

/* Starts watching `count` values (at most IC_MAX_VALUES) at `values`, with an
 * internal step of h seconds, the inputs expected every `period` seconds (0 or
 * less than h: every internal step). */
void ic_init(InputCadence *c, int count, const double values[], double h, double period);

/* `steps` internal steps with `values` held. */
void ic_advance(InputCadence *c, const double values[], unsigned long long steps);

/* The shortest hold of the last complete window in which the inputs changed
 * twice, in internal steps (0: no such window yet), and whether it is a
 * staircase (longer than expected, and CADENCE_COARSE_STEPS at least). */
int ic_shortest(const InputCadence *c);
int ic_coarse(const InputCadence *c);

/* A restored state's invariant between fields: the window's age below its length. */
int ic_valid(const InputCadence *c);

#endif
