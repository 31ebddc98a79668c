/* The output-grid loop of the native fast path (see ode_loop.h). */
#include "ode_loop.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

const char *ode_loop_error_string(int code) {
    switch (code) {
    case ODE_LOOP_ERR_GRID: return "the time grid must be finite and strictly increasing";
    case ODE_LOOP_ERR_STATE: return "the initial state is not finite";
    case ODE_LOOP_ERR_INPUT: return "an input is not finite, or the number of input rows is neither 1 nor n_grid - 1";
    case ODE_LOOP_ERR_NULL: return "a required pointer is NULL";
    default: return ode_error_string(code);
    }
}

/* What the solver's x' = f(x) callbacks need: the model, and the input held on the current interval. */
typedef struct {
    const OdeModel *model;
    const double *u;
    const double *p;
} LoopContext;

static int loop_rhs(void *ctx, const double *x, double *xdot) {
    const LoopContext *c = (const LoopContext *)ctx;
    return c->model->rhs(c->model->ctx, x, c->u, c->p, xdot);
}

static int loop_jac(void *ctx, const double *x, double *J) {
    const LoopContext *c = (const LoopContext *)ctx;
    return c->model->jac(c->model->ctx, x, c->u, c->p, J);
}

static int finite_all(const double *v, long n) {
    for (long i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static void fill_stats(OdeLoopStats *stats, const OdeSolver *s, double t, int n_points) {
    if (stats == NULL) return;
    stats->n_steps = s->n_steps;
    stats->n_rejected = s->n_rejected;
    stats->n_rhs = s->n_rhs;
    stats->n_jac = s->n_jac;
    stats->t_reached = t;
    stats->h_next = s->h;
    stats->n_points = n_points;
    stats->reserved = 0;
}

int ode_run_grid(const OdeLoopSettings *settings, const OdeModel *model, const double *t_grid, int n_grid,
                 const double *u, int u_rows, const double *p, const double *x0, double *x_out, OdeLoopStats *stats) {
    OdeSolver s;
    memset(&s, 0, sizeof(s));
    if (stats != NULL) memset(stats, 0, sizeof(*stats));
    if (settings == NULL || model == NULL || t_grid == NULL || x0 == NULL || x_out == NULL || model->rhs == NULL)
        return ODE_LOOP_ERR_NULL;
    if (settings->method == ODE_RODAS4 && model->jac == NULL) return ODE_LOOP_ERR_NULL;
    if (model->nu < 0) return ODE_ERR_ARGS;
    if (model->nu > 0 && u == NULL) return ODE_LOOP_ERR_NULL;
    if (settings->max_steps < 1 || !isfinite(settings->h0) || settings->h0 < 0.0) return ODE_ERR_ARGS;
    int rc = ode_init(&s, model->nx, settings->method, settings->rtol, settings->atol, settings->h_max);
    if (rc != ODE_OK) return rc;
    if (n_grid < 1 || !isfinite(t_grid[0])) return ODE_LOOP_ERR_GRID;
    for (int k = 1; k < n_grid; k++)
        if (!isfinite(t_grid[k]) || !(t_grid[k] > t_grid[k - 1])) return ODE_LOOP_ERR_GRID;
    if (u_rows != 1 && (n_grid < 2 || u_rows != n_grid - 1)) return ODE_LOOP_ERR_INPUT;
    if (model->nu > 0 && !finite_all(u, (long)u_rows * model->nu)) return ODE_LOOP_ERR_INPUT;
    const int nx = model->nx;
    if (!finite_all(x0, nx)) return ODE_LOOP_ERR_STATE;

    s.h = settings->h0;
    double t = t_grid[0];
    double x[ODE_MAX_N];
    memcpy(x, x0, sizeof(double) * (size_t)nx);
    memcpy(x_out, x0, sizeof(double) * (size_t)nx);
    int n_points = 1;
    LoopContext ctx = {model, u, p};
    for (int k = 0; k + 1 < n_grid; k++) {
        long used = s.n_steps + s.n_rejected;
        if (used >= settings->max_steps) {
            rc = ODE_ERR_MAX_STEPS;
            break;
        }
        s.max_steps = settings->max_steps - used; /* ode_integrate's limit is per call: spend what is left */
        ctx.u = (model->nu > 0 && u_rows > 1) ? u + (size_t)k * (size_t)model->nu : u;
        rc = ode_integrate(&s, loop_rhs, settings->method == ODE_RODAS4 ? loop_jac : NULL, &ctx, &t, x, t_grid[k + 1]);
        if (rc != ODE_OK) break;
        memcpy(x_out + (size_t)(k + 1) * (size_t)nx, x, sizeof(double) * (size_t)nx);
        n_points++;
    }
    fill_stats(stats, &s, t, n_points);
    return rc;
}

int ode_loop_rhs_repeat(const OdeModel *model, const double *x, const double *u, const double *p, long n_calls,
                        double *xdot) {
    if (model == NULL || model->rhs == NULL || x == NULL || xdot == NULL || (model->nu > 0 && u == NULL))
        return ODE_LOOP_ERR_NULL;
    LoopContext ctx = {model, u, p};
    ode_rhs_fn f = loop_rhs; /* called through a pointer, as ode_integrate calls it */
    for (long i = 0; i < n_calls; i++) {
        int rc = f(&ctx, x, xdot);
        if (rc != 0) return rc;
    }
    return ODE_OK;
}
