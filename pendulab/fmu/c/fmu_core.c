/* Model core shared by the FMI 2 and FMI 3 layers (see fmu_core.h). */
#include "fmu_core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static const double X_START[MODEL_NX] = MODEL_X_START;
static const double P_DEFAULT[MODEL_NP] = MODEL_P_DEFAULT;
static const int P_TUNABLE[MODEL_NP] = MODEL_P_TUNABLE;
static const int P_POSITIVE[MODEL_NP] = MODEL_P_POSITIVE;
static const char *const P_NAMES[MODEL_NP] = MODEL_P_NAMES;

/* A communication point may differ from the FMU's time by accumulated rounding in the master. */
#define TIME_RTOL 1e-9

/* Spring-length states of the elastic model (the model is singular at r = 0): by convention the elastic
 * state is (theta1, theta2, r1, r2, omega1, omega2, v1, v2). Every path a state takes (setters,
 * SetContinuousStates, FMU states, the solver's result) requires r > 0, as pendulab.simulate does. */
#ifndef MODEL_NR
#if MODEL_NX == 8
#define MODEL_R_INDEX 2
#define MODEL_NR 2
#else
#define MODEL_R_INDEX 0
#define MODEL_NR 0
#endif
#endif
#define MODEL_P_L 2 /* parameters m1, m2, L1, L2, ...: the rest lengths L1, L2 are at 2, 3 */

void core_defaults(Instance *inst) {
    CoreData *d = &inst->d;
    memset(d, 0, sizeof(*d));
    d->magic = MODEL_MAGIC;
    d->machine = MS_INSTANTIATED;
    d->time = 0.0;
    memcpy(d->x, X_START, sizeof(d->x));
    memcpy(d->p, P_DEFAULT, sizeof(d->p));
    d->tolerance = MODEL_TOL_DEFAULT;
    d->max_step = MODEL_HMAX_DEFAULT;
    d->solver = MODEL_SOLVER_DEFAULT;
    inst->terminate_requested = 0;
    inst->event_pending = 0;
}

static void vlog(Instance *inst, CoreStatus status, const char *category, const char *fmt, va_list ap) {
    char msg[512];
    if (inst == NULL || inst->log == NULL) return;
    vsnprintf(msg, sizeof(msg), fmt, ap);
    inst->log(inst, status, category, msg);
}

void core_logf(Instance *inst, CoreStatus status, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vlog(inst, status, status >= ST_ERROR ? "logStatusError" : "logStatusWarning", fmt, ap);
    va_end(ap);
}

void core_debugf(Instance *inst, const char *fmt, ...) {
    va_list ap;
    if (inst == NULL || !inst->logging_on) return;
    va_start(ap, fmt);
    vlog(inst, ST_OK, "logCalls", fmt, ap);
    va_end(ap);
}

const char *core_machine_name(int machine) {
    switch (machine) {
    case MS_INSTANTIATED: return "Instantiated";
    case MS_INIT: return "InitializationMode";
    case MS_STEP: return "StepMode";
    case MS_EVENT: return "EventMode";
    case MS_CONT: return "ContinuousTimeMode";
    case MS_TERMINATED: return "Terminated";
    case MS_ERROR: return "Error";
    default: return "unknown";
    }
}

CoreStatus core_check(Instance *inst, int allowed, const char *fname) {
    if (inst->d.machine & allowed) return ST_OK;
    core_logf(inst, ST_ERROR, "%s: not allowed in state %s", fname, core_machine_name(inst->d.machine));
    return ST_ERROR;
}

VarKind core_classify(unsigned int vr, int *index) {
    *index = 0;
    if (vr == MODEL_VR_TIME) return KIND_TIME;
#define RANGE(base, n, kind)                                                                                          \
    if (vr >= (unsigned)(base) && vr < (unsigned)(base) + (unsigned)(n)) {                                            \
        *index = (int)(vr - (unsigned)(base));                                                                        \
        return kind;                                                                                                  \
    }
    RANGE(MODEL_VR_X, MODEL_NX, KIND_STATE)
    RANGE(MODEL_VR_DX, MODEL_NX, KIND_DERIV)
    RANGE(MODEL_VR_U, MODEL_NU, KIND_INPUT)
    RANGE(MODEL_VR_Y, MODEL_NY, KIND_OUTPUT)
    RANGE(MODEL_VR_P, MODEL_NP, KIND_PARAM)
    RANGE(MODEL_VR_Z, MODEL_NZ, KIND_INDICATOR)
#undef RANGE
    if (vr == MODEL_VR_TOL) return KIND_TOL;
    if (vr == MODEL_VR_HMAX) return KIND_HMAX;
    if (vr == MODEL_VR_SOLVER) return KIND_SOLVER;
    return KIND_NONE;
}

/* ------------------------------------------------------------ model calls */
static int eval(Instance *inst, casadi_fn fn, const double *x, double *out0) {
    inst->arg[0] = x;
    inst->arg[1] = inst->d.u;
    inst->arg[2] = inst->d.p;
    inst->res[0] = out0;
    return fn(inst->arg, inst->res, inst->iw, inst->w, 0);
}

static int rhs_cb(void *ctx, const double *x, double *xdot) { return eval((Instance *)ctx, MODEL_RHS, x, xdot); }
static int jac_cb(void *ctx, const double *x, double *J) { return eval((Instance *)ctx, MODEL_JAC_X, x, J); }

static int all_finite(const double *v, int n) {
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* Index of the first spring length <= 0 in x, or -1 (NaN counts as invalid too). */
static int bad_spring_length(const double *x) {
    for (int i = 0; i < MODEL_NR; i++)
        if (!(x[MODEL_R_INDEX + i] > 0.0)) return MODEL_R_INDEX + i;
    return -1;
}

#ifndef MODEL_NF
#define MODEL_NF 0
#endif
#define CORE_PI 3.14159265358979323846

/* Event indicator k: spring margins first (k < MODEL_NR), then flip margins pi - |theta_j| (export option):
 * 0 when link j passes the upright position; a flip changes nothing in the model, the importer just stops
 * its integrator there (Model Exchange). */
static double indicator(const CoreData *d, int k);
static int flipped(const CoreData *a, const CoreData *b);
static CoreStatus locate_flip(Instance *inst, const CoreData *before, double t_end);

/* Spring margin i (event indicator): r_i - MODEL_SPRING_LIMIT * L_i. */
static double spring_margin(const CoreData *d, const double *x, int i) {
    return x[MODEL_R_INDEX + i] - MODEL_SPRING_LIMIT * d->p[MODEL_P_L + i];
}

/* Index (0-based) of the first spring at or below its limit at x, or -1 (NaN counts as reached). */
static int spring_at_limit(const CoreData *d, const double *x) {
    for (int i = 0; i < MODEL_NR; i++)
        if (!(spring_margin(d, x, i) > 0.0)) return i;
    return -1;
}

CoreStatus core_event_indicators(Instance *inst, double *z, size_t n, const char *fname) {
    if (n != MODEL_NZ || (n > 0 && z == NULL)) {
        core_logf(inst, ST_ERROR, "%s: the model has %d event indicators, got n = %zu%s", fname, MODEL_NZ, n,
                  z == NULL && n > 0 ? " and a NULL array" : "");
        return ST_ERROR;
    }
    for (int k = 0; k < MODEL_NZ; k++) z[k] = indicator(&inst->d, k);
    return ST_OK;
}

static double indicator(const CoreData *d, int k) {
    if (k < MODEL_NR) return spring_margin(d, d->x, k);
    return CORE_PI - fabs(d->x[k - MODEL_NR]); /* theta1, theta2 are the first two states */
}

int core_spring_event(Instance *inst, const char *fname) {
    int i = spring_at_limit(&inst->d, inst->d.x);
    if (i < 0) return 0;
    core_logf(inst, ST_WARNING, "%s: spring %d reached %g m = %g x L%d at t = %.17g (the model is singular at r = 0): "
              "terminate the simulation", fname, i + 1, inst->d.x[MODEL_R_INDEX + i], MODEL_SPRING_LIMIT, i + 1,
              inst->d.time);
    return 1;
}

/* The one rule for a state vector, wherever it comes from (setters, ME states, FMU states, the solver). */
static CoreStatus check_state_vector(Instance *inst, const double *x, const char *fname) {
    for (int i = 0; i < MODEL_NX; i++)
        if (!isfinite(x[i])) {
            core_logf(inst, ST_ERROR, "%s: state %d (value reference %d) is not finite: %g", fname, i, MODEL_VR_X + i, x[i]);
            return ST_ERROR;
        }
    int r = bad_spring_length(x);
    if (r >= 0) {
        core_logf(inst, ST_ERROR, "%s: spring length r%d (value reference %d) must be > 0, got %g", fname,
                  r - MODEL_R_INDEX + 1, MODEL_VR_X + r, x[r]);
        return ST_ERROR;
    }
    return ST_OK;
}

/* The setter's rule for parameter k (also applied to restored FMU states). */
static CoreStatus check_param(Instance *inst, int k, double v, const char *fname) {
    if (!isfinite(v)) {
        core_logf(inst, ST_ERROR, "%s: parameter %s: value %g is not finite", fname, P_NAMES[k], v);
        return ST_ERROR;
    }
    if (P_POSITIVE[k] ? !(v > 0.0) : !(v >= 0.0)) {
        core_logf(inst, ST_ERROR, "%s: parameter %s must be %s, got %g", fname, P_NAMES[k], P_POSITIVE[k] ? "> 0" : ">= 0", v);
        return ST_ERROR;
    }
    return ST_OK;
}

static CoreStatus check_tolerance(Instance *inst, double v, const char *fname) {
    if (!(v > 0.0) || !(v < 1.0)) {
        core_logf(inst, ST_ERROR, "%s: solver_tolerance must be in (0, 1), got %g", fname, v);
        return ST_ERROR;
    }
    return ST_OK;
}

static CoreStatus check_max_step(Instance *inst, double v, const char *fname) {
    if (!isfinite(v) || v < 0.0) {
        core_logf(inst, ST_ERROR, "%s: max_step must be finite and >= 0 (0: unlimited), got %g", fname, v);
        return ST_ERROR;
    }
    return ST_OK;
}

CoreStatus core_derivatives(Instance *inst, double *xdot) {
    if (eval(inst, MODEL_RHS, inst->d.x, xdot) != 0 || !all_finite(xdot, MODEL_NX)) {
        core_logf(inst, ST_ERROR, "the right-hand side could not be evaluated (non-finite result) at t = %g", inst->d.time);
        return ST_ERROR;
    }
    return ST_OK;
}

static CoreStatus outputs(Instance *inst, double *y) {
    if (eval(inst, MODEL_OUTPUTS, inst->d.x, y) != 0 || !all_finite(y, MODEL_NY)) {
        core_logf(inst, ST_ERROR, "the outputs could not be evaluated (non-finite result) at t = %g", inst->d.time);
        return ST_ERROR;
    }
    return ST_OK;
}

/* ------------------------------------------------------------ get / set */
static const int GET_ALLOWED = MS_INIT | MS_STEP | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR;

CoreStatus core_get_real(Instance *inst, const char *fname, const unsigned int *vr, size_t n, double *value) {
    if (core_check(inst, GET_ALLOWED, fname) != ST_OK) return ST_ERROR;
    if (n > 0 && (vr == NULL || value == NULL)) {
        core_logf(inst, ST_ERROR, "%s: NULL value reference or value array with n = %zu", fname, n);
        return ST_ERROR;
    }
    double y[MODEL_NY], xdot[MODEL_NX];
    int have_y = 0, have_xdot = 0;
    for (size_t i = 0; i < n; i++) {
        int k;
        switch (core_classify(vr[i], &k)) {
        case KIND_TIME: value[i] = inst->d.time; break;
        case KIND_STATE: value[i] = inst->d.x[k]; break;
        case KIND_DERIV:
            if (!have_xdot && core_derivatives(inst, xdot) != ST_OK) return ST_ERROR;
            have_xdot = 1;
            value[i] = xdot[k];
            break;
        case KIND_INPUT: value[i] = inst->d.u[k]; break;
        case KIND_OUTPUT:
            if (!have_y && outputs(inst, y) != ST_OK) return ST_ERROR;
            have_y = 1;
            value[i] = y[k];
            break;
        case KIND_PARAM: value[i] = inst->d.p[k]; break;
        case KIND_TOL: value[i] = inst->d.tolerance; break;
        case KIND_HMAX: value[i] = inst->d.max_step; break;
        case KIND_INDICATOR: value[i] = indicator(&inst->d, k); break;
        default:
            core_logf(inst, ST_ERROR, "%s: unknown value reference %u for a real variable", fname, vr[i]);
            return ST_ERROR;
        }
    }
    return ST_OK;
}

/* A changed solver setting discards the set-up solver (ExitInitializationMode or the next DoStep sets it
 * up again), so that an FMU state never holds a solver block inconsistent with its settings. */
static void invalidate_solver(Instance *inst) { memset(&inst->d.ode, 0, sizeof(inst->d.ode)); }

static CoreStatus set_one_real(Instance *inst, const char *fname, unsigned int vr, double v) {
    int k;
    const int before_run = MS_INSTANTIATED | MS_INIT;
    VarKind kind = core_classify(vr, &k);
    if (kind == KIND_NONE || kind == KIND_SOLVER) {
        core_logf(inst, ST_ERROR, "%s: unknown value reference %u for a real variable", fname, vr);
        return ST_ERROR;
    }
    if (!isfinite(v)) {
        core_logf(inst, ST_ERROR, "%s: value reference %u: value %g is not finite", fname, vr, v);
        return ST_ERROR;
    }
    switch (kind) {
    case KIND_STATE:
        if (core_check(inst, before_run, fname) != ST_OK) return ST_ERROR;
        if (k >= MODEL_R_INDEX && k < MODEL_R_INDEX + MODEL_NR && !(v > 0.0)) {
            core_logf(inst, ST_ERROR, "%s: spring length r%d (value reference %u) must be > 0, got %g", fname,
                      k - MODEL_R_INDEX + 1, vr, v);
            return ST_ERROR;
        }
        inst->d.x[k] = v;
        return ST_OK;
    case KIND_INPUT:
        if (core_check(inst, before_run | MS_STEP | MS_EVENT | MS_CONT, fname) != ST_OK) return ST_ERROR;
        inst->d.u[k] = v;
        return ST_OK;
    case KIND_PARAM:
        if (core_check(inst, P_TUNABLE[k] ? (before_run | MS_STEP | MS_EVENT) : before_run, fname) != ST_OK) {
            core_logf(inst, ST_ERROR, "%s: parameter %s is %s", fname, P_NAMES[k],
                      P_TUNABLE[k] ? "tunable only in step or event mode" : "fixed after initialization");
            return ST_ERROR;
        }
        if (check_param(inst, k, v, fname) != ST_OK) return ST_ERROR;
        inst->d.p[k] = v;
        return ST_OK;
    case KIND_TOL:
        if (core_check(inst, before_run, fname) != ST_OK) return ST_ERROR;
        if (check_tolerance(inst, v, fname) != ST_OK) return ST_ERROR;
        inst->d.tolerance = v;
        invalidate_solver(inst);
        return ST_OK;
    case KIND_HMAX:
        if (core_check(inst, before_run, fname) != ST_OK) return ST_ERROR;
        if (check_max_step(inst, v, fname) != ST_OK) return ST_ERROR;
        inst->d.max_step = v;
        invalidate_solver(inst);
        return ST_OK;
    default:
        core_logf(inst, ST_ERROR, "%s: value reference %u (time, derivative or output) cannot be set", fname, vr);
        return ST_ERROR;
    }
}

CoreStatus core_set_real(Instance *inst, const char *fname, const unsigned int *vr, size_t n, const double *value) {
    if (core_check(inst, MS_INSTANTIATED | MS_INIT | MS_STEP | MS_EVENT | MS_CONT, fname) != ST_OK) return ST_ERROR;
    if (n > 0 && (vr == NULL || value == NULL)) {
        core_logf(inst, ST_ERROR, "%s: NULL value reference or value array with n = %zu", fname, n);
        return ST_ERROR;
    }
    /* validate everything first so that a rejected call changes nothing */
    CoreData saved = inst->d;
    for (size_t i = 0; i < n; i++) {
        if (set_one_real(inst, fname, vr[i], value[i]) != ST_OK) {
            inst->d = saved;
            return ST_ERROR;
        }
    }
    return ST_OK;
}

CoreStatus core_get_int(Instance *inst, const char *fname, const unsigned int *vr, size_t n, int *value) {
    if (core_check(inst, GET_ALLOWED, fname) != ST_OK) return ST_ERROR;
    if (n > 0 && (vr == NULL || value == NULL)) {
        core_logf(inst, ST_ERROR, "%s: NULL value reference or value array with n = %zu", fname, n);
        return ST_ERROR;
    }
    for (size_t i = 0; i < n; i++) {
        int k;
        if (core_classify(vr[i], &k) != KIND_SOLVER) {
            core_logf(inst, ST_ERROR, "%s: unknown value reference %u for an integer variable", fname, vr[i]);
            return ST_ERROR;
        }
        value[i] = inst->d.solver;
    }
    return ST_OK;
}

CoreStatus core_set_int(Instance *inst, const char *fname, const unsigned int *vr, size_t n, const int *value) {
    /* the only integer variable, solver, is a fixed parameter */
    if (core_check(inst, MS_INSTANTIATED | MS_INIT, fname) != ST_OK) return ST_ERROR;
    if (n > 0 && (vr == NULL || value == NULL)) {
        core_logf(inst, ST_ERROR, "%s: NULL value reference or value array with n = %zu", fname, n);
        return ST_ERROR;
    }
    for (size_t i = 0; i < n; i++) { /* validate all before changing anything */
        int k;
        if (core_classify(vr[i], &k) != KIND_SOLVER) {
            core_logf(inst, ST_ERROR, "%s: unknown value reference %u for an integer variable", fname, vr[i]);
            return ST_ERROR;
        }
        if (value[i] != ODE_DOPRI5 && value[i] != ODE_RODAS4) {
            core_logf(inst, ST_ERROR, "%s: solver must be 0 (dopri5) or 1 (rodas4), got %d", fname, value[i]);
            return ST_ERROR;
        }
    }
    for (size_t i = 0; i < n; i++) inst->d.solver = value[i];
    if (n > 0) invalidate_solver(inst);
    return ST_OK;
}

/* ------------------------------------------------------------ life cycle */
CoreStatus core_set_experiment(Instance *inst, int tolerance_defined, double tolerance, double start_time) {
    if (!isfinite(start_time)) {
        core_logf(inst, ST_ERROR, "start time must be finite, got %g", start_time);
        return ST_ERROR;
    }
    if (tolerance_defined) {
        if (!(tolerance > 0.0) || !(tolerance < 1.0)) {
            core_logf(inst, ST_ERROR, "tolerance must be in (0, 1), got %g", tolerance);
            return ST_ERROR;
        }
        inst->d.tolerance = tolerance;
        inst->d.tolerance_from_master = 1;
        invalidate_solver(inst);
    }
    inst->d.time = start_time;
    return ST_OK;
}

static CoreStatus solver_setup(Instance *inst, const char *fname) {
    CoreData *d = &inst->d;
    int rc = ode_init(&d->ode, MODEL_NX, d->solver, d->tolerance, d->tolerance, d->max_step);
    if (rc != ODE_OK) {
        core_logf(inst, ST_ERROR, "%s: solver setup failed: %s", fname, ode_error_string(rc));
        return ST_ERROR;
    }
    d->ode.max_steps = CORE_MAX_INTERNAL_STEPS;
    return ST_OK;
}

CoreStatus core_exit_initialization(Instance *inst) {
    if (check_state_vector(inst, inst->d.x, "ExitInitializationMode: initial state") != ST_OK) return ST_ERROR;
    if (solver_setup(inst, "ExitInitializationMode") != ST_OK) return ST_ERROR;
    double y[MODEL_NY];
    if (outputs(inst, y) != ST_OK) return ST_ERROR;
    core_debugf(inst, "initialized at t = %g with solver %s, tolerance %g (%s), max_step %g", inst->d.time,
                inst->d.solver == ODE_RODAS4 ? "rodas4" : "dopri5", inst->d.tolerance,
                inst->d.tolerance_from_master ? "from the master" : "parameter solver_tolerance", inst->d.max_step);
    return ST_OK;
}

CoreStatus core_do_step(Instance *inst, double current, double h) {
    CoreData *d = &inst->d;
    if (!isfinite(current) || !isfinite(h) || !(h > 0.0) || !isfinite(current + h)) {
        core_logf(inst, ST_ERROR, "DoStep: communication step size must be positive and finite (and end at a finite time), "
                  "got %g at point %g", h, current);
        return ST_ERROR;
    }
    if (inst->terminate_requested) {
        core_logf(inst, ST_DISCARD, "DoStep: the simulation was ended at t = %.17g (a spring reached its limit); "
                  "call Terminate, or restore an earlier FMU state", d->time);
        return ST_DISCARD;
    }
    if (fabs(current - d->time) > TIME_RTOL * fmax(1.0, fabs(d->time))) {
        core_logf(inst, ST_ERROR, "DoStep: communication point %.17g does not match the FMU time %.17g", current, d->time);
        return ST_ERROR;
    }
    if (d->ode.n != MODEL_NX) { /* e.g. an FMU state saved during initialization was restored */
        if (solver_setup(inst, "DoStep") != ST_OK) return ST_ERROR;
    }
    double t = d->time;
    double t_end = current + h;
    double span = t_end - t;
    if (span < CORE_MIN_SOLVER_SPAN * fmax(1.0, fabs(t))) {
        /* Below the solver's resolution (its smallest step is 1e-14 max(1, |t|)): one explicit Euler step,
         * whose error h^2 |x''| / 2 is far below the rounding of x; a span <= 0 (the master's communication
         * point is up to TIME_RTOL behind the FMU time) changes nothing. Time never runs backwards. */
        if (span > 0.0) {
            double xdot[MODEL_NX], x1[MODEL_NX];
            if (core_derivatives(inst, xdot) != ST_OK) {
                d->machine = MS_ERROR;
                return ST_ERROR;
            }
            for (int i = 0; i < MODEL_NX; i++) x1[i] = d->x[i] + span * xdot[i];
            if (check_state_vector(inst, x1, "DoStep") != ST_OK) {
                d->machine = MS_ERROR;
                return ST_ERROR;
            }
            memcpy(d->x, x1, sizeof(d->x));
            d->time = t_end;
        }
        core_debugf(inst, "DoStep: step %g below the solver resolution at t = %.17g: Euler step", h, t);
        return ST_OK;
    }
    const CoreData before = *d; /* the start of the step, for locating a spring limit */
    int rc = ode_integrate(&d->ode, rhs_cb, jac_cb, inst, &t, d->x, t_end);
    d->time = t;
    if (MODEL_NR > 0 && (rc != ODE_OK || spring_at_limit(d, d->x) >= 0)) {
        /* Locate the limit: redo the step in CORE_EVENT_SUBSTEPS equal sub-steps from its start and stop at the
         * last one with every spring above its limit. A failure without a spring at its limit stays a failure. */
        *d = before;
        double t0 = before.time;
        for (int k = 1; k <= CORE_EVENT_SUBSTEPS; k++) {
            double tk = k == CORE_EVENT_SUBSTEPS ? t_end : t0 + (t_end - t0) * k / CORE_EVENT_SUBSTEPS;
            CoreData keep = *d;
            t = d->time;
            rc = ode_integrate(&d->ode, rhs_cb, jac_cb, inst, &t, d->x, tk);
            d->time = t;
            int spring = spring_at_limit(d, d->x);
            if (spring >= 0) {
                double r = d->x[MODEL_R_INDEX + spring], t_hit = t;
                *d = keep;
                inst->terminate_requested = 1;
                core_logf(inst, ST_DISCARD, "DoStep: spring %d reached %g m (limit %g x L%d) between t = %.17g and "
                          "%.17g (the model is singular at r = 0): the FMU stops at t = %.17g; terminate the "
                          "simulation", spring + 1, r, MODEL_SPRING_LIMIT, spring + 1, keep.time, t_hit, keep.time);
                return ST_DISCARD;
            }
            if (rc != ODE_OK) break;
        }
    }
    if (rc != ODE_OK) {
        d->machine = MS_ERROR; /* bad arguments leave the instance usable; a solver failure does not */
        core_logf(inst, ST_ERROR, "DoStep: %s solver failed at t = %.17g (target %.17g): %s%s",
                  d->solver == ODE_RODAS4 ? "rodas4" : "dopri5", t, t_end, ode_error_string(rc),
                  rc == ODE_ERR_MAX_STEPS ? " (at most " CORE_MAX_INTERNAL_STEPS_TEXT " per communication step)" : "");
        return ST_ERROR;
    }
    if (check_state_vector(inst, d->x, "DoStep: state reached by the solver") != ST_OK) {
        d->machine = MS_ERROR; /* the trajectory left the model's domain (a spring length reached 0) */
        return ST_ERROR;
    }
    inst->event_pending = 0;
    if (MODEL_NF > 0 && inst->event_mode_used && flipped(&before, d)) {
        inst->event_pending = 1;
        if (inst->early_return) return locate_flip(inst, &before, t_end);
        core_debugf(inst, "DoStep: a link passed upright during the step ending at t = %.17g", d->time);
    }
    return ST_OK;
}

/* 1 when a flip indicator has a different sign at b than at a. */
static int flipped(const CoreData *a, const CoreData *b) {
    for (int k = MODEL_NR; k < MODEL_NZ; k++)
        if ((indicator(a, k) > 0.0) != (indicator(b, k) > 0.0)) return 1;
    return 0;
}

/* Bisection for the first flip in (before.time, t_end]: re-integrate from the latest point known to lie before
 * it; the FMU ends at the first point found past it (within CORE_EVENT_TIME_RTOL max(1, |t|)). */
static CoreStatus locate_flip(Instance *inst, const CoreData *before, double t_end) {
    CoreData lo = *before, past = inst->d; /* past: a state after the flip (the end of the step) */
    double t_hi = t_end;
    for (int it = 0; it < 200 && t_hi - lo.time > CORE_EVENT_TIME_RTOL * fmax(1.0, fabs(t_hi)); it++) {
        CoreData mid = lo;
        double t = mid.time, t_mid = 0.5 * (lo.time + t_hi);
        if (ode_integrate(&mid.ode, rhs_cb, jac_cb, inst, &t, mid.x, t_mid) != ODE_OK) break;
        mid.time = t;
        if (flipped(&lo, &mid)) {
            t_hi = t_mid;
            past = mid;
        } else {
            lo = mid;
        }
    }
    inst->d = past;
    core_debugf(inst, "DoStep: a link passes upright at t = %.17g: early return for event handling", past.time);
    return ST_OK;
}

CoreStatus core_set_states(Instance *inst, const double *x, size_t n) {
    if (x == NULL || n != MODEL_NX) {
        core_logf(inst, ST_ERROR, "SetContinuousStates: expected %d states and a non-NULL array, got n = %zu", MODEL_NX, n);
        return ST_ERROR;
    }
    if (check_state_vector(inst, x, "SetContinuousStates: states must be finite and valid") != ST_OK) return ST_ERROR;
    memcpy(inst->d.x, x, sizeof(inst->d.x));
    return ST_OK;
}

CoreStatus core_set_time(Instance *inst, double t) {
    if (!isfinite(t)) {
        core_logf(inst, ST_ERROR, "SetTime: time must be finite, got %g", t);
        return ST_ERROR;
    }
    inst->d.time = t;
    return ST_OK;
}

/* ------------------------------------------------------------ derivatives */
CoreStatus core_directional(Instance *inst, const unsigned int *unknown, size_t n_unknown, const unsigned int *known,
                            size_t n_known, const double *seed, double *sensitivity) {
    enum { NR = MODEL_NX + MODEL_NY, NC = MODEL_NX + MODEL_NU };
    double J[NR * NC];
    if ((n_unknown > 0 && (unknown == NULL || sensitivity == NULL)) || (n_known > 0 && (known == NULL || seed == NULL))) {
        core_logf(inst, ST_ERROR, "GetDirectionalDerivative: NULL array argument");
        return ST_ERROR;
    }
    int rows[NR > 0 ? NR : 1], cols[NC > 0 ? NC : 1];
    if (n_unknown > NR || n_known > NC) {
        core_logf(inst, ST_ERROR, "GetDirectionalDerivative: too many unknowns (%zu) or knowns (%zu)", n_unknown, n_known);
        return ST_ERROR;
    }
    for (size_t i = 0; i < n_unknown; i++) {
        int k;
        VarKind kind = core_classify(unknown[i], &k);
        if (kind == KIND_DERIV) rows[i] = k;
        else if (kind == KIND_OUTPUT) rows[i] = MODEL_NX + k;
        else {
            core_logf(inst, ST_ERROR, "GetDirectionalDerivative: unknown %u is not a derivative or output", unknown[i]);
            return ST_ERROR;
        }
    }
    for (size_t j = 0; j < n_known; j++) {
        int k;
        VarKind kind = core_classify(known[j], &k);
        if (kind == KIND_STATE) cols[j] = k;
        else if (kind == KIND_INPUT) cols[j] = MODEL_NX + k;
        else {
            core_logf(inst, ST_ERROR, "GetDirectionalDerivative: known %u is not a state or input", known[j]);
            return ST_ERROR;
        }
        if (!isfinite(seed[j])) {
            core_logf(inst, ST_ERROR, "GetDirectionalDerivative: seed %zu is not finite", j);
            return ST_ERROR;
        }
    }
    if (eval(inst, MODEL_JAC_ALL, inst->d.x, J) != 0 || !all_finite(J, NR * NC)) {
        core_logf(inst, ST_ERROR, "GetDirectionalDerivative: Jacobian evaluation failed");
        return ST_ERROR;
    }
    for (size_t i = 0; i < n_unknown; i++) {
        double acc = 0.0;
        for (size_t j = 0; j < n_known; j++) acc += J[rows[i] + NR * cols[j]] * seed[j];
        sensitivity[i] = acc;
    }
    return ST_OK;
}

/* ------------------------------------------------------------ FMU state */
static int is_machine_state(int m) {
    return m == MS_INSTANTIATED || m == MS_INIT || m == MS_STEP || m == MS_EVENT || m == MS_CONT || m == MS_TERMINATED;
}

/* Every field of an FMU state passes the checks its setter applies; the solver block is either unset
 * (saved before initialization) or consistent with the settings. Nothing is changed. */
static CoreStatus validate_data(Instance *inst, const CoreData *d, const char *fname) {
    char what[160];
    if (d->magic != MODEL_MAGIC) {
        core_logf(inst, ST_ERROR, "%s: FMU state was not produced by this model (%s)", fname, MODEL_IDENTIFIER);
        return ST_ERROR;
    }
    if (!is_machine_state(d->machine)) {
        core_logf(inst, ST_ERROR, "%s: FMU state holds an invalid life-cycle state %d", fname, d->machine);
        return ST_ERROR;
    }
    if (!isfinite(d->time)) {
        core_logf(inst, ST_ERROR, "%s: FMU state: time %g is not finite", fname, d->time);
        return ST_ERROR;
    }
    snprintf(what, sizeof(what), "%s: FMU state", fname);
    if (check_state_vector(inst, d->x, what) != ST_OK) return ST_ERROR;
    for (int i = 0; i < MODEL_NU; i++)
        if (!isfinite(d->u[i])) {
            core_logf(inst, ST_ERROR, "%s: FMU state: input %d (value reference %d) is not finite: %g", fname, i,
                      MODEL_VR_U + i, d->u[i]);
            return ST_ERROR;
        }
    for (int k = 0; k < MODEL_NP; k++)
        if (check_param(inst, k, d->p[k], what) != ST_OK) return ST_ERROR;
    if (check_tolerance(inst, d->tolerance, what) != ST_OK || check_max_step(inst, d->max_step, what) != ST_OK)
        return ST_ERROR;
    if (d->solver != ODE_DOPRI5 && d->solver != ODE_RODAS4) {
        core_logf(inst, ST_ERROR, "%s: FMU state: solver must be 0 (dopri5) or 1 (rodas4), got %d", fname, d->solver);
        return ST_ERROR;
    }
    if (d->tolerance_from_master != 0 && d->tolerance_from_master != 1) {
        core_logf(inst, ST_ERROR, "%s: FMU state: invalid tolerance flag %d", fname, d->tolerance_from_master);
        return ST_ERROR;
    }
    const OdeSolver *o = &d->ode;
    if (o->n == 0) return ST_OK; /* saved before initialization: the solver is set up at the next step */
    if (o->n != MODEL_NX || o->method != d->solver || o->rtol != d->tolerance || o->atol != d->tolerance ||
        o->h_max != d->max_step || o->max_steps < 1 || o->max_steps > CORE_MAX_INTERNAL_STEPS || !isfinite(o->h) ||
        o->h < 0.0 || o->n_steps < 0 || o->n_rejected < 0 || o->n_rhs < 0 || o->n_jac < 0) {
        core_logf(inst, ST_ERROR, "%s: FMU state: the solver settings (n = %d, method %d, tolerance %g, max_step %g, "
                  "step guess %g) are inconsistent with the model settings", fname, o->n, o->method, o->rtol, o->h_max, o->h);
        return ST_ERROR;
    }
    return ST_OK;
}

CoreStatus core_check_state_blob(Instance *inst, const void *blob, size_t size, const char *fname) {
    CoreData tmp;
    if (blob == NULL || size != sizeof(CoreData)) {
        core_logf(inst, ST_ERROR, "%s: FMU state is NULL or has %zu bytes, expected %zu", fname, size, sizeof(CoreData));
        return ST_ERROR;
    }
    memcpy(&tmp, blob, sizeof(tmp)); /* the blob may be unaligned (a serialized byte buffer) */
    return validate_data(inst, &tmp, fname);
}

int core_is_state_block(const void *p) {
    unsigned long first;
    memcpy(&first, p, sizeof(first)); /* p points to at least a pointer's worth of memory either way */
    return first == MODEL_MAGIC;
}

CoreStatus core_restore(Instance *inst, const CoreData *saved, const char *fname) {
    if (core_check_state_blob(inst, saved, sizeof(CoreData), fname) != ST_OK) return ST_ERROR;
    /* The instance resumes the life-cycle state stored with the FMU state, as the Reference FMUs do: a fresh
     * instance (Instantiated) restored from a serialized state taken in step mode is in step mode (fmusim's
     * resume-from-file flow: instantiate -> restore -> step), and a restart from a state stored before an
     * error is possible (FMI 2.0 section 2.1.3, FMI 3.0 section 2.2.3). Only a state of the other interface
     * (an ME event/continuous-time state into a CS instance, a CS step state into an ME instance) is refused. */
    int machine = saved->machine;
    int legal = inst->is_cosim ? (MS_INSTANTIATED | MS_INIT | MS_STEP | MS_TERMINATED | (inst->event_mode_used ? MS_EVENT : 0))
                               : (MS_INSTANTIATED | MS_INIT | MS_EVENT | MS_CONT | MS_TERMINATED);
    if (!(machine & legal)) {
        core_logf(inst, ST_ERROR, "%s: FMU state was taken in %s, which a %s instance cannot resume", fname,
                  core_machine_name(machine), inst->is_cosim ? "Co-Simulation" : "Model Exchange");
        return ST_ERROR;
    }
    memcpy(&inst->d, saved, sizeof(CoreData)); /* the blob may be unaligned (a deserialized byte buffer) */
    inst->terminate_requested = 0;
    inst->event_pending = 0;
    return ST_OK;
}
