/* Adaptive one-step ODE solvers: Dormand-Prince 5(4) and RODAS4 (Rosenbrock 4(3)).
 *
 * References: Hairer, Norsett, Wanner, Solving ODEs I (dopri5.f) and Hairer,
 * Wanner, Solving ODEs II, section IV.7 (rodas.f, method RODAS4; the stage
 * form used here is the one of Sandu et al.'s KPP Rosenbrock code).
 */
#include "ode_solver.h"

#include <math.h>
#include <string.h>

#define SAFETY 0.9
#define FAC_MIN 0.2
#define FAC_MAX 6.0

const char *ode_error_string(int code) {
    switch (code) {
    case ODE_OK: return "ok";
    case ODE_ERR_RHS: return "the right-hand side failed or returned a non-finite value";
    case ODE_ERR_STEP_SIZE: return "step size underflow (solution blows up or tolerance too tight)";
    case ODE_ERR_MAX_STEPS: return "too many internal steps in one call";
    case ODE_ERR_SINGULAR: return "singular iteration matrix";
    case ODE_ERR_ARGS: return "bad solver arguments";
    default: return "unknown solver error";
    }
}

int ode_init(OdeSolver *s, int n, int method, double rtol, double atol, double h_max) {
    if (s == NULL || n < 1 || n > ODE_MAX_N || (method != ODE_DOPRI5 && method != ODE_RODAS4)) return ODE_ERR_ARGS;
    if (!(rtol > 0.0) || !(atol > 0.0) || !isfinite(rtol) || !isfinite(atol) || isnan(h_max)) return ODE_ERR_ARGS;
    memset(s, 0, sizeof(*s));
    s->n = n;
    s->method = method;
    s->rtol = rtol;
    s->atol = atol;
    s->h_max = h_max;
    s->max_steps = 10000000L;
    s->h = 0.0;
    return ODE_OK;
}

static int all_finite(int n, const double *v) {
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static int call_f(OdeSolver *s, ode_rhs_fn f, void *ctx, const double *x, double *xdot) {
    s->n_rhs++;
    if (f(ctx, x, xdot) != 0 || !all_finite(s->n, xdot)) return ODE_ERR_RHS;
    return ODE_OK;
}

/* Weighted RMS norm of err with scale atol + rtol*max(|x0|,|x1|). */
static double err_norm(const OdeSolver *s, const double *err, const double *x0, const double *x1) {
    double sum = 0.0;
    for (int i = 0; i < s->n; i++) {
        double sc = s->atol + s->rtol * fmax(fabs(x0[i]), fabs(x1[i]));
        double r = err[i] / sc;
        sum += r * r;
    }
    return sqrt(sum / s->n);
}

/* Starting step (Hairer's HINIT, simplified): order is the method's error order. */
static int initial_step(OdeSolver *s, ode_rhs_fn f, void *ctx, const double *x, const double *f0, double span,
                        int order, double *h_out) {
    int n = s->n;
    double d0 = 0.0, d1 = 0.0, x1[ODE_MAX_N], f1[ODE_MAX_N];
    for (int i = 0; i < n; i++) {
        double sc = s->atol + s->rtol * fabs(x[i]);
        d0 += (x[i] / sc) * (x[i] / sc);
        d1 += (f0[i] / sc) * (f0[i] / sc);
    }
    d0 = sqrt(d0 / n);
    d1 = sqrt(d1 / n);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = fmin(h0, span);
    for (int i = 0; i < n; i++) x1[i] = x[i] + h0 * f0[i];
    int rc = call_f(s, f, ctx, x1, f1);
    if (rc != ODE_OK) {
        *h_out = 1e-6 * span; /* let the step-size control recover */
        return ODE_OK;
    }
    double d2 = 0.0;
    for (int i = 0; i < n; i++) {
        double sc = s->atol + s->rtol * fabs(x[i]);
        double r = (f1[i] - f0[i]) / sc;
        d2 += r * r;
    }
    d2 = sqrt(d2 / n) / h0;
    double dm = fmax(d1, d2);
    double h1 = dm <= 1e-15 ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / dm, 1.0 / (order + 1));
    *h_out = fmin(100.0 * h0, h1);
    return ODE_OK;
}

/* ---------------------------------------------------------------- dense LU */
static int lu_factor(int n, double *A, int *piv) { /* column-major, in place */
    for (int k = 0; k < n; k++) {
        int p = k;
        double amax = fabs(A[k + k * n]);
        for (int i = k + 1; i < n; i++)
            if (fabs(A[i + k * n]) > amax) {
                amax = fabs(A[i + k * n]);
                p = i;
            }
        piv[k] = p;
        if (amax == 0.0 || !isfinite(amax)) return ODE_ERR_SINGULAR;
        if (p != k)
            for (int j = 0; j < n; j++) {
                double tmp = A[k + j * n];
                A[k + j * n] = A[p + j * n];
                A[p + j * n] = tmp;
            }
        double inv = 1.0 / A[k + k * n];
        for (int i = k + 1; i < n; i++) A[i + k * n] *= inv;
        for (int j = k + 1; j < n; j++) {
            double akj = A[k + j * n];
            if (akj != 0.0)
                for (int i = k + 1; i < n; i++) A[i + j * n] -= A[i + k * n] * akj;
        }
    }
    return ODE_OK;
}

static void lu_solve(int n, const double *LU, const int *piv, double *b) {
    /* lu_factor swaps whole rows, so the stored L is in final row order: permute b first */
    for (int k = 0; k < n; k++) {
        int p = piv[k];
        if (p != k) {
            double tmp = b[k];
            b[k] = b[p];
            b[p] = tmp;
        }
    }
    for (int k = 0; k < n; k++)
        for (int i = k + 1; i < n; i++) b[i] -= LU[i + k * n] * b[k];
    for (int k = n - 1; k >= 0; k--) {
        b[k] /= LU[k + k * n];
        for (int i = 0; i < k; i++) b[i] -= LU[i + k * n] * b[k];
    }
}

/* ---------------------------------------------------------------- DOPRI5 */
static const double DP_A[7][6] = {
    {0, 0, 0, 0, 0, 0},
    {1.0 / 5, 0, 0, 0, 0, 0},
    {3.0 / 40, 9.0 / 40, 0, 0, 0, 0},
    {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0},
    {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84},
};
/* fifth-order solution minus embedded fourth-order solution */
static const double DP_E[7] = {71.0 / 57600, 0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200, 22.0 / 525, -1.0 / 40};

/* ---------------------------------------------------------------- RODAS4 */
#define RS 6
static const double RO_GAMMA = 0.25;
static const double RO_A[RS][RS] = {
    {0, 0, 0, 0, 0, 0},
    {1.544000000000000, 0, 0, 0, 0, 0},
    {0.9466785280815826, 0.2557011698983284, 0, 0, 0, 0},
    {3.314825187068521, 2.896124015972201, 0.9986419139977817, 0, 0, 0},
    {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 0, 0},
    {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0, 0},
};
static const double RO_C[RS][RS] = {
    {0, 0, 0, 0, 0, 0},
    {-5.668800000000000, 0, 0, 0, 0, 0},
    {-2.430093356833875, -0.2063599157091915, 0, 0, 0, 0},
    {-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0, 0, 0},
    {7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160, 0, 0},
    {8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, -6.058818238834054, 0},
};
static const double RO_M[RS] = {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0, 1.0};

int ode_integrate(OdeSolver *s, ode_rhs_fn f, ode_jac_fn jac, void *ctx, double *t, double *x, double t_end) {
    if (s == NULL || f == NULL || t == NULL || x == NULL) return ODE_ERR_ARGS;
    if (s->method == ODE_RODAS4 && jac == NULL) return ODE_ERR_ARGS;
    if (!isfinite(*t) || !isfinite(t_end) || !(t_end > *t)) return ODE_ERR_ARGS;
    const int n = s->n;
    const int implicit = s->method == ODE_RODAS4;
    const int order = implicit ? 4 : 5; /* exponent base for step-size control: 1 + embedded order */
    double k[7][ODE_MAX_N], xs[ODE_MAX_N], xn[ODE_MAX_N], err[ODE_MAX_N];
    double J[ODE_MAX_N * ODE_MAX_N], W[ODE_MAX_N * ODE_MAX_N];
    int piv[ODE_MAX_N];
    int rc;
    double f0[ODE_MAX_N];

    if ((rc = call_f(s, f, ctx, x, f0)) != ODE_OK) return rc;
    double span = t_end - *t;
    double h = s->h;
    if (!(h > 0.0)) {
        if ((rc = initial_step(s, f, ctx, x, f0, span, order, &h)) != ODE_OK) return rc;
    }
    if (s->h_max > 0.0) h = fmin(h, s->h_max);
    int have_jac = 0, last_rejected = 0;
    long steps = 0;
    while (*t < t_end) {
        if (++steps > s->max_steps) return ODE_ERR_MAX_STEPS;
        double h_proposed = h;
        int last = 0;
        /* stretch the final step by up to 1 % rather than leave a sliver */
        if (*t + 1.01 * h >= t_end) {
            h = t_end - *t;
            last = 1;
        }
        if (h < 1e-14 * fmax(1.0, fabs(*t))) return ODE_ERR_STEP_SIZE;

        double en;
        if (!implicit) {
            memcpy(k[0], f0, sizeof(double) * n);
            for (int st = 1; st < 7; st++) {
                for (int i = 0; i < n; i++) {
                    double acc = 0.0;
                    for (int j = 0; j < st; j++) acc += DP_A[st][j] * k[j][i];
                    xs[i] = x[i] + h * acc;
                }
                if ((rc = call_f(s, f, ctx, xs, k[st])) != ODE_OK) break;
                if (st == 6) memcpy(xn, xs, sizeof(double) * n); /* FSAL: stage 7 point = 5th-order solution */
            }
            if (rc != ODE_OK) {
                en = INFINITY; /* treat a failed evaluation in a trial step as a rejection */
            } else {
                for (int i = 0; i < n; i++) {
                    double acc = 0.0;
                    for (int j = 0; j < 7; j++) acc += DP_E[j] * k[j][i];
                    err[i] = h * acc;
                }
                en = err_norm(s, err, x, xn);
            }
        } else {
            if (!have_jac) {
                s->n_jac++;
                if (jac(ctx, x, J) != 0 || !all_finite(n * n, J)) return ODE_ERR_RHS;
                have_jac = 1;
            }
            double d = 1.0 / (h * RO_GAMMA);
            for (int i = 0; i < n * n; i++) W[i] = -J[i];
            for (int i = 0; i < n; i++) W[i + i * n] += d;
            rc = lu_factor(n, W, piv);
            if (rc == ODE_OK) {
                for (int st = 0; st < RS && rc == ODE_OK; st++) {
                    double *F = k[st];
                    if (st == 0) {
                        memcpy(F, f0, sizeof(double) * n);
                    } else {
                        for (int i = 0; i < n; i++) {
                            double acc = 0.0;
                            for (int j = 0; j < st; j++) acc += RO_A[st][j] * k[j][i];
                            xs[i] = x[i] + acc;
                        }
                        rc = call_f(s, f, ctx, xs, F);
                        if (rc != ODE_OK) break;
                        for (int i = 0; i < n; i++) {
                            double acc = 0.0;
                            for (int j = 0; j < st; j++) acc += RO_C[st][j] * k[j][i];
                            F[i] += acc / h;
                        }
                    }
                    lu_solve(n, W, piv, F); /* k[st] now holds the stage increment */
                }
            }
            if (rc != ODE_OK) {
                en = INFINITY;
            } else {
                for (int i = 0; i < n; i++) {
                    double acc = 0.0;
                    for (int j = 0; j < RS; j++) acc += RO_M[j] * k[j][i];
                    xn[i] = x[i] + acc;
                    err[i] = d * k[RS - 1][i];
                }
                /* Shampine's filter (as in Hairer's RADAU5): err := (I - h*gamma*J)^-1 err. It leaves
                 * non-stiff error components unchanged and damps the stiff ones, which the L-stable step
                 * damps too; without it an undamped stiff oscillation (a stiff spring) of any amplitude
                 * forces the step size down to resolve it. */
                lu_solve(n, W, piv, err);
                en = all_finite(n, xn) ? err_norm(s, err, x, xn) : INFINITY;
            }
        }

        double fac;
        if (!isfinite(en)) {
            fac = FAC_MIN;
        } else {
            fac = en > 0.0 ? SAFETY * pow(en, -1.0 / order) : FAC_MAX;
            fac = fmin(FAC_MAX, fmax(FAC_MIN, fac));
        }
        if (en <= 1.0) {
            s->n_steps++;
            *t = last ? t_end : *t + h;
            memcpy(x, xn, sizeof(double) * n);
            if (!implicit) {
                memcpy(f0, k[6], sizeof(double) * n);
            } else if (*t < t_end) {
                if ((rc = call_f(s, f, ctx, x, f0)) != ODE_OK) return rc;
                have_jac = 0;
            }
            if (last_rejected) fac = fmin(fac, 1.0);
            last_rejected = 0;
            /* a final step shortened to hit t_end says nothing about the next step size */
            h = (last && h < h_proposed) ? fmax(h_proposed, h * fac) : h * fac;
        } else {
            s->n_rejected++;
            last_rejected = 1;
            h = h * fmin(fac, 1.0);
        }
        if (s->h_max > 0.0) h = fmin(h, s->h_max);
    }
    s->h = h;
    return ODE_OK;
}
