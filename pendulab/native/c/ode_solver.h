/* Adaptive one-step ODE solvers for x' = f(x) (autonomous over one call).
 *
 * Independent of FMI: the FMU layer and any native compiled fast path drive
 * them through the callbacks below. The solver keeps no pointers into its own
 * storage and no history beyond the next step-size guess, so copying an
 * OdeSolver by value (memcpy) copies its complete state: FMU state
 * get/set/serialize is bit-identical.
 */
#ifndef PENDULAB_ODE_SOLVER_H
#define PENDULAB_ODE_SOLVER_H

#define ODE_MAX_N 16

enum { ODE_DOPRI5 = 0, ODE_RODAS4 = 1 };

enum {
    ODE_OK = 0,
    ODE_ERR_RHS = -1,       /* right-hand side returned an error or a non-finite value */
    ODE_ERR_STEP_SIZE = -2, /* step size underflow */
    ODE_ERR_MAX_STEPS = -3, /* too many steps in one call */
    ODE_ERR_SINGULAR = -4,  /* singular iteration matrix (implicit method) */
    ODE_ERR_ARGS = -5       /* bad arguments (size, tolerance, direction) */
};

/* f(ctx, x, xdot): return 0 on success. */
typedef int (*ode_rhs_fn)(void *ctx, const double *x, double *xdot);
/* jac(ctx, x, J): dense df/dx, column-major n x n; return 0 on success. */
typedef int (*ode_jac_fn)(void *ctx, const double *x, double *J);

typedef struct {
    int n;
    int method;          /* ODE_DOPRI5 or ODE_RODAS4 */
    double rtol, atol;   /* mixed error test: |err_i| <= atol + rtol*max(|x_i|,|x_new_i|) */
    double h_max;        /* largest internal step; <= 0: unlimited */
    long max_steps;      /* per call of ode_integrate */
    double h;            /* next step-size guess; 0: choose automatically */
    /* statistics (cumulative) */
    long n_steps, n_rejected, n_rhs, n_jac;
} OdeSolver;

/* Initialise with defaults; returns ODE_ERR_ARGS on a bad size or method. */
int ode_init(OdeSolver *s, int n, int method, double rtol, double atol, double h_max);

/* Advance x from t to t_end (t_end > t) with error control; on success *t == t_end exactly.
 * On failure x and *t hold the last accepted step. */
int ode_integrate(OdeSolver *s, ode_rhs_fn f, ode_jac_fn jac, void *ctx, double *t, double *x, double t_end);

const char *ode_error_string(int code);

#endif
