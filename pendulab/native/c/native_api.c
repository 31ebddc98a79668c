/* Entry points of the native library (see native_api.h); the per-kind constants come from the
 * generated header native_model.h. */
#include "native_api.h"

#include <stddef.h>

#include "native_model.h"

#define ARRAY_SIZE(n) ((n) > 0 ? (n) : 1)

typedef int (*casadi_fn)(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w, int mem);

/* CasADi work arrays of one run (on the caller's stack: no global state). */
typedef struct {
    const casadi_real *arg[ARRAY_SIZE(NATIVE_SZ_ARG)];
    casadi_real *res[ARRAY_SIZE(NATIVE_SZ_RES)];
    casadi_int iw[ARRAY_SIZE(NATIVE_SZ_IW)];
    casadi_real w[ARRAY_SIZE(NATIVE_SZ_W)];
} Work;

static int eval(Work *work, casadi_fn fn, const double *x, const double *u, const double *p, double *out) {
    work->arg[0] = x;
    work->arg[1] = u;
    work->arg[2] = p;
    work->res[0] = out;
    return fn(work->arg, work->res, work->iw, work->w, 0);
}

static int model_rhs(void *ctx, const double *x, const double *u, const double *p, double *xdot) {
    return eval((Work *)ctx, NATIVE_RHS, x, u, p, xdot);
}

static int model_jac(void *ctx, const double *x, const double *u, const double *p, double *J) {
    return eval((Work *)ctx, NATIVE_JAC_X, x, u, p, J);
}

int pendulab_native_abi(void) { return PENDULAB_NATIVE_ABI; }

void pendulab_native_sizes(int *nx, int *nu, int *np, int *stats_bytes) {
    if (nx != NULL) *nx = NATIVE_NX;
    if (nu != NULL) *nu = NATIVE_NU;
    if (np != NULL) *np = NATIVE_NP;
    if (stats_bytes != NULL) *stats_bytes = (int)sizeof(OdeLoopStats);
}

const char *pendulab_native_error_string(int code) { return ode_loop_error_string(code); }

int pendulab_native_run(int method, double rtol, double atol, double h_max, long max_steps, double h0,
                        const double *t_grid, int n_grid, const double *u, int u_rows, const double *p,
                        const double *x0, double *x_out, OdeLoopStats *stats) {
    if (p == NULL) return ODE_LOOP_ERR_NULL;
    Work work;
    OdeModel model = {NATIVE_NX, NATIVE_NU, model_rhs, model_jac, &work};
    OdeLoopSettings settings = {method, rtol, atol, h_max, max_steps, h0};
    return ode_run_grid(&settings, &model, t_grid, n_grid, u, u_rows, p, x0, x_out, stats);
}

int pendulab_native_rhs(const double *x, const double *u, const double *p, double *xdot) {
    if (x == NULL || u == NULL || p == NULL || xdot == NULL) return ODE_LOOP_ERR_NULL;
    Work work;
    return eval(&work, NATIVE_RHS, x, u, p, xdot);
}

int pendulab_native_jac(const double *x, const double *u, const double *p, double *J) {
    if (x == NULL || u == NULL || p == NULL || J == NULL) return ODE_LOOP_ERR_NULL;
    Work work;
    return eval(&work, NATIVE_JAC_X, x, u, p, J);
}

int pendulab_native_rhs_repeat(int path, long n_calls, const double *x, const double *u, const double *p,
                               double *xdot) {
    if (x == NULL || u == NULL || p == NULL || xdot == NULL) return ODE_LOOP_ERR_NULL;
    if (n_calls < 0 || (path != 0 && path != 1)) return ODE_ERR_ARGS;
    Work work;
    if (path == 1) {
        OdeModel model = {NATIVE_NX, NATIVE_NU, model_rhs, model_jac, &work};
        return ode_loop_rhs_repeat(&model, x, u, p, n_calls, xdot);
    }
    work.arg[0] = x;
    work.arg[1] = u;
    work.arg[2] = p;
    work.res[0] = xdot;
    for (long i = 0; i < n_calls; i++) {
        int rc = NATIVE_RHS(work.arg, work.res, work.iw, work.w, 0);
        if (rc != 0) return rc;
    }
    return ODE_OK;
}
