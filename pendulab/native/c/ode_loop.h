/* The output-grid loop of the native fast path: one call integrates a whole grid.
 *
 * From t_grid[0] to t_grid[n_grid-1], interval by interval, with the solvers of
 * ode_solver.h, holding the input of each interval constant (zero-order hold, as
 * a co-simulation master does), and writes the state at every grid point into the
 * caller's buffer. One OdeSolver runs the whole grid, carrying its step-size guess
 * from interval to interval exactly as an FMU does across DoStep calls: the same
 * model code and the same solver settings give the same numbers through both.
 *
 * C99, no global mutable state; every argument is validated.
 */
#ifndef PENDULAB_ODE_LOOP_H
#define PENDULAB_ODE_LOOP_H

#include "ode_solver.h"

/* Error codes of the loop besides those of ode_solver.h (ODE_OK ... ODE_ERR_ARGS). */
enum {
    ODE_LOOP_ERR_GRID = -10,  /* grid not finite and strictly increasing, or fewer than 1 point */
    ODE_LOOP_ERR_STATE = -11, /* initial state not finite */
    ODE_LOOP_ERR_INPUT = -12, /* an input value not finite, or a bad number of input rows */
    ODE_LOOP_ERR_NULL = -13   /* a required pointer is NULL */
};

/* A model with inputs and parameters: out = f(x, u, p) (rhs: nx values; jac: nx*nx, column-major).
 * Return 0 on success. */
typedef int (*ode_model_fn)(void *ctx, const double *x, const double *u, const double *p, double *out);

typedef struct {
    int nx, nu;
    ode_model_fn rhs;
    ode_model_fn jac; /* required by ODE_RODAS4, may be NULL for ODE_DOPRI5 */
    void *ctx;
} OdeModel;

typedef struct {
    int method;         /* ODE_DOPRI5 or ODE_RODAS4 */
    double rtol, atol;  /* see OdeSolver */
    double h_max;       /* largest internal step; <= 0: unlimited */
    long max_steps;     /* budget of step attempts (accepted + rejected) over the whole call, >= 1 */
    double h0;          /* first step-size guess; 0: choose automatically */
} OdeLoopSettings;

typedef struct {
    long n_steps, n_rejected, n_rhs, n_jac; /* this call's counts */
    double t_reached; /* last time reached: t_grid[n_grid-1] on success, else the last accepted step */
    double h_next;    /* the solver's next step-size guess (pass as h0 to continue seamlessly) */
    int n_points;     /* rows of x_out written (x0 included) */
    int reserved;
} OdeLoopStats;

/* Integrate over t_grid (n_grid points, strictly increasing, finite).
 * u: u_rows x nu, row-major; u_rows = 1 holds one input over the whole grid, u_rows = n_grid - 1 holds
 *    row k on [t_grid[k], t_grid[k+1]]. May be NULL when nu = 0.
 * p: parameter vector passed through to the model functions (may be NULL if they do not read it).
 * x0: nx initial values; x_out: n_grid x nx, row-major, not overlapping x0; row 0 is x0.
 * stats may be NULL. Returns ODE_OK or a negative error code; on failure the rows up to
 * stats->n_points - 1 are valid and stats->t_reached tells where the solver stopped. */
int ode_run_grid(const OdeLoopSettings *settings, const OdeModel *model, const double *t_grid, int n_grid,
                 const double *u, int u_rows, const double *p, const double *x0, double *x_out, OdeLoopStats *stats);

/* Evaluate the model's right-hand side n_calls times at (x, u, p) through the same callback chain the
 * solver uses inside ode_run_grid (for measuring the per-call cost of that path). Returns the first
 * non-zero status of the model function, else 0. */
int ode_loop_rhs_repeat(const OdeModel *model, const double *x, const double *u, const double *p, long n_calls,
                        double *xdot);

/* Message of a code of ode_run_grid (covers those of ode_solver.h). */
const char *ode_loop_error_string(int code);

#endif
