/* Continuous-time least squares (LSM), eqs. (18)-(19), and its matrix
 * forgetting factor version (MFF), eqs. (36)-(37), of Davila, Fridman and
 * Poznyak (2006), driven by the filtered equivalent output injection:
 *     z = Delta * phi,   Delta (rows x m) unknown,  phi (m) the regressor.
 * Plain C, no FMI types. */
#ifndef IDENTIFIER_H
#define IDENTIFIER_H

#define ID_MAX_ROWS 4
#define ID_MAX_REGRESSORS 8

typedef enum { IDENTIFIER_OFF = 0, IDENTIFIER_LSM = 1, IDENTIFIER_MFF = 2 } IdentifierKind;

typedef struct {
    int kind;
    int rows;     /* n: one row of Delta per degree of freedom */
    int m;        /* number of identified regressors */
    double h;     /* integration step [s] */
    double h_log_r; /* h * ln R for MFF (R per second, scalar R*I), 0 for LSM */
    double delta[ID_MAX_ROWS][ID_MAX_REGRESSORS];
    double gamma[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS]; /* symmetric */
} Identifier;

/* Delta = 0, Gamma = I / rho.  R is used by MFF only. */
void identifier_init(Identifier *id, IdentifierKind kind, int rows, int m, double h, double rho,
                     double R);

/* One sample of the regression z = Delta phi (rows entries of z, m of phi). */
typedef struct {
    double z[ID_MAX_ROWS];
    double phi[ID_MAX_REGRESSORS];
} IdSample;

/* A sample from separate arrays (the one-sample steps). */
static inline IdSample identifier_sample(int rows, int m, const double z[], const double phi[])
{
    IdSample sample = {{0}, {0}};
    for (int i = 0; i < rows && i < ID_MAX_ROWS; ++i) sample.z[i] = z[i];
    for (int k = 0; k < m && k < ID_MAX_REGRESSORS; ++k) sample.phi[k] = phi[k];
    return sample;
}

/* One explicit Euler step of (18)/(37) and (19)/(36). */
void identifier_step(Identifier *id, const double z[], const double phi[]);

/* identifier_step over `count` samples in turn. */
void identifier_run(Identifier *id, const IdSample samples[], int count);

double identifier_gamma_trace(const Identifier *id);

#endif
