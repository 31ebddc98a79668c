/* Core of a pendulab controller FMU: sample-and-hold, variables, life cycle. See ctrl_core.h. */
#include "ctrl_core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static const char *machine_name(int m) {
    switch (m) {
    case CMS_INSTANTIATED: return "Instantiated";
    case CMS_INIT: return "InitializationMode";
    case CMS_STEP: return "StepMode";
    case CMS_TERMINATED: return "Terminated";
    case CMS_ERROR: return "Error";
    default: return "invalid";
    }
}

void ctrl_logf(CtrlInstance *inst, CtrlStatus status, const char *fmt, ...) {
    char msg[512];
    va_list ap;
    if (inst == NULL || inst->log == NULL) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    inst->log(inst, status, status >= CST_ERROR ? "logStatusError" : status == CST_WARNING ? "logStatusWarning" : "logCalls", msg);
}

void ctrl_defaults(CtrlInstance *inst) {
    static const double x_start[CTRL_NX] = CTRL_X_START;
    memset(&inst->d, 0, sizeof(inst->d));
    inst->d.magic = CTRL_MAGIC;
    inst->d.machine = CMS_INSTANTIATED;
    inst->d.sample_time = CTRL_SAMPLE_TIME;
    memcpy(inst->d.x, x_start, sizeof(x_start));
}

CtrlStatus ctrl_check(CtrlInstance *inst, int allowed, const char *fname) {
    if (inst->d.machine & allowed) return CST_OK;
    ctrl_logf(inst, CST_ERROR, "%s: not allowed in state %s", fname, machine_name(inst->d.machine));
    return CST_ERROR;
}

static void clip(double *u, int n, double limit) {
    if (!(limit > 0.0)) return; /* no limit */
    for (int i = 0; i < n; i++) u[i] = fmin(fmax(u[i], -limit), limit); /* as numpy.clip */
}

static int call(CtrlInstance *inst, casadi_fn fn, const double *a0, const double *a1, const double *a2, const double *a3,
                double *r0, double *r1) {
    inst->arg[0] = a0;
    if (CTRL_SZ_ARG > 1) inst->arg[1 % CTRL_SZ_ARG] = a1;
    if (CTRL_SZ_ARG > 2) inst->arg[2 % CTRL_SZ_ARG] = a2;
    if (CTRL_SZ_ARG > 3) inst->arg[3 % CTRL_SZ_ARG] = a3;
    inst->res[0] = r0;
    if (CTRL_SZ_RES > 1) inst->res[1 % CTRL_SZ_RES] = r1;
    return fn(inst->arg, inst->res, inst->iw, inst->w, 0);
}

/* The control law at sample time ts with inputs x: torques into u; *mode is the switching state (updated). */
static int law(CtrlInstance *inst, double ts, const double *x, int *mode, double *u) {
    double cost = 0.0;
    (void)ts;
    (void)mode;
    (void)cost;
#if CTRL_KIND == CTRL_KIND_LQR
    if (call(inst, CTRL_FN_BALANCE, x, NULL, NULL, NULL, u, &cost) != 0) return 1;
    *mode = 1;
#elif CTRL_KIND == CTRL_KIND_SWINGUP
    double ub[CTRL_NU];
    if (call(inst, CTRL_FN_BALANCE, x, NULL, NULL, NULL, ub, &cost) != 0) return 1;
    if (!*mode && cost < CTRL_CATCH_COST) *mode = 1;
    else if (*mode && CTRL_RELEASE_FACTOR > 0.0 && cost > CTRL_RELEASE_FACTOR * CTRL_CATCH_COST) *mode = 0; /* failed catch */
    if (*mode) memcpy(u, ub, sizeof(ub));
    else if (call(inst, CTRL_FN_PUMP, x, NULL, NULL, NULL, u, NULL) != 0) return 1;
#elif CTRL_KIND == CTRL_KIND_TVLQR
    /* k: the last reference time at or before ts (+ a hair of a sample), by bisection over the increasing grid */
    double tq = ts + CTRL_SAMPLE_SLACK * CTRL_DESIGN_SAMPLE_TIME;
    long lo = 0, hi = CTRL_NT; /* count of t_ref <= tq lies in [lo, hi] */
    while (lo < hi) {
        long mid = lo + (hi - lo) / 2;
        if (ctrl_t_ref[mid] <= tq) lo = mid + 1;
        else hi = mid;
    }
    long k = lo - 1;
    if (k >= CTRL_NK) {
        *mode = 1;
#if CTRL_HAS_BALANCE
        if (call(inst, CTRL_FN_BALANCE, x, NULL, NULL, NULL, u, &cost) != 0) return 1;
#else
        memcpy(u, ctrl_u_ref + (CTRL_NU_ROWS - 1) * CTRL_NU, sizeof(double) * CTRL_NU);
#endif
    } else {
        if (k < 0) k = 0;
        *mode = 0;
        if (call(inst, CTRL_FN_TRACK, x, ctrl_x_ref + k * CTRL_NX, ctrl_u_ref + k * CTRL_NU, ctrl_k_ref + k * CTRL_NU * CTRL_NX, u,
                 NULL) != 0)
            return 1;
    }
#else
#error "unknown CTRL_KIND"
#endif
    clip(u, CTRL_NU, CTRL_U_MAX);
    for (int i = 0; i < CTRL_NU; i++)
        if (!isfinite(u[i])) return 1;
    return 0;
}

static double sample_instant(const CtrlData *d, long k) { return d->start_time + (double)k * d->sample_time; }

/* Is the current time the (uncommitted) next sample instant? */
static int sample_due(const CtrlData *d) {
    return d->machine != CMS_INSTANTIATED &&
           fabs(d->time - sample_instant(d, d->next_sample)) <= CTRL_SAMPLE_SLACK * d->sample_time;
}

static CtrlStatus commit(CtrlInstance *inst, const char *fname) {
    double ts = sample_instant(&inst->d, inst->d.next_sample);
    if (law(inst, ts, inst->d.x, &inst->d.mode, inst->d.u) != 0) {
        ctrl_logf(inst, CST_ERROR, "%s: the control law failed at t = %.17g s (non-finite torque)", fname, ts);
        return CST_ERROR;
    }
    inst->d.next_sample++;
    return CST_OK;
}

/* ------------------------------------------------------------ variables */
typedef enum { V_NONE, V_TIME, V_X, V_U, V_H } VarKind;

static VarKind classify(unsigned int vr, int *index) {
    if (vr == CTRL_VR_TIME) return V_TIME;
    if (vr >= CTRL_VR_X && vr < CTRL_VR_X + CTRL_NX) return *index = (int)(vr - CTRL_VR_X), V_X;
    if (vr >= CTRL_VR_U && vr < CTRL_VR_U + CTRL_NU) return *index = (int)(vr - CTRL_VR_U), V_U;
    if (vr == CTRL_VR_SAMPLE_TIME) return V_H;
    return V_NONE;
}

CtrlStatus ctrl_get_real(CtrlInstance *inst, const char *fname, const unsigned int *vr, size_t n, double *value) {
    if (ctrl_check(inst, CMS_INIT | CMS_STEP | CMS_TERMINATED | CMS_ERROR, fname) != CST_OK) return CST_ERROR;
    if (n > 0 && (vr == NULL || value == NULL)) {
        ctrl_logf(inst, CST_ERROR, "%s: NULL array argument with n = %zu", fname, n);
        return CST_ERROR;
    }
    int due = sample_due(&inst->d), evaluated = 0, mode = inst->d.mode;
    double u[CTRL_NU];
    for (size_t i = 0; i < n; i++) {
        int k = 0;
        switch (classify(vr[i], &k)) {
        case V_TIME: value[i] = inst->d.time; break;
        case V_X: value[i] = inst->d.x[k]; break;
        case V_H: value[i] = inst->d.sample_time; break;
        case V_U:
            if (!due) {
                value[i] = inst->d.u[k];
                break;
            }
            if (!evaluated) { /* at a sample instant: the law at the current inputs, not yet committed */
                if (law(inst, sample_instant(&inst->d, inst->d.next_sample), inst->d.x, &mode, u) != 0) {
                    ctrl_logf(inst, CST_ERROR, "%s: the control law failed (non-finite torque)", fname);
                    return CST_ERROR;
                }
                evaluated = 1;
            }
            value[i] = u[k];
            break;
        default:
            ctrl_logf(inst, CST_ERROR, "%s: no Float64 variable with value reference %u", fname, vr[i]);
            return CST_ERROR;
        }
    }
    return CST_OK;
}

CtrlStatus ctrl_set_real(CtrlInstance *inst, const char *fname, const unsigned int *vr, size_t n, const double *value) {
    if (ctrl_check(inst, CMS_INSTANTIATED | CMS_INIT | CMS_STEP, fname) != CST_OK) return CST_ERROR;
    if (n > 0 && (vr == NULL || value == NULL)) {
        ctrl_logf(inst, CST_ERROR, "%s: NULL array argument with n = %zu", fname, n);
        return CST_ERROR;
    }
    for (size_t i = 0; i < n; i++) { /* check all, then set: a refused call changes nothing */
        int k = 0;
        VarKind kind = classify(vr[i], &k);
        if (kind == V_X) {
            if (!isfinite(value[i])) {
                ctrl_logf(inst, CST_ERROR, "%s: input %s (value reference %u) must be finite, got %g", fname, ctrl_x_names[k], vr[i],
                          value[i]);
                return CST_ERROR;
            }
        } else if (kind == V_H) {
            if (!(inst->d.machine & (CMS_INSTANTIATED | CMS_INIT))) {
                ctrl_logf(inst, CST_ERROR, "%s: sample_time is a fixed parameter: set it before initialization ends", fname);
                return CST_ERROR;
            }
            if (!(isfinite(value[i]) && value[i] > 0.0)) {
                ctrl_logf(inst, CST_ERROR, "%s: sample_time must be a positive finite period [s], got %g", fname, value[i]);
                return CST_ERROR;
            }
        } else {
            ctrl_logf(inst, CST_ERROR, "%s: value reference %u is not an input or parameter (outputs and time are read-only)", fname,
                      vr[i]);
            return CST_ERROR;
        }
    }
    for (size_t i = 0; i < n; i++) {
        int k = 0;
        if (classify(vr[i], &k) == V_X) inst->d.x[k] = value[i];
        else inst->d.sample_time = value[i];
    }
    return CST_OK;
}

/* ------------------------------------------------------------ life cycle */
CtrlStatus ctrl_check_tolerance(CtrlInstance *inst, int defined, double tolerance, const char *fname) {
    if (!defined || (tolerance > 0.0 && tolerance < 1.0)) return CST_OK;
    ctrl_logf(inst, CST_ERROR, "%s: tolerance must be in (0, 1), got %g", fname, tolerance);
    return CST_ERROR;
}

CtrlStatus ctrl_enter_initialization(CtrlInstance *inst, double start_time, const char *fname) {
    if (ctrl_check(inst, CMS_INSTANTIATED, fname) != CST_OK) return CST_ERROR;
    if (!isfinite(start_time)) {
        ctrl_logf(inst, CST_ERROR, "%s: start time must be finite, got %g", fname, start_time);
        return CST_ERROR;
    }
    inst->d.start_time = inst->d.time = start_time;
    inst->d.next_sample = 0;
    inst->d.mode = 0;
    inst->d.machine = CMS_INIT;
    return CST_OK;
}

CtrlStatus ctrl_exit_initialization(CtrlInstance *inst, const char *fname) {
    if (ctrl_check(inst, CMS_INIT, fname) != CST_OK) return CST_ERROR;
    inst->d.machine = CMS_STEP;
    return CST_OK;
}

CtrlStatus ctrl_do_step(CtrlInstance *inst, double current, double h, const char *fname) {
    if (ctrl_check(inst, CMS_STEP, fname) != CST_OK) return CST_ERROR;
    CtrlData *d = &inst->d;
    double slack = CTRL_SAMPLE_SLACK * d->sample_time;
    if (!isfinite(current) || !isfinite(h) || !(h > 0.0) || !isfinite(current + h)) {
        /* as the plant FMUs and the Reference FMUs: a step of size 0 (or negative, NaN, Inf) is an Error */
        ctrl_logf(inst, CST_ERROR,
                  "%s: communication step size must be positive and finite (and end at a finite time), got %g at point %g", fname,
                  h, current);
        return CST_ERROR;
    }
    if (fabs(current - d->time) > slack + 1e-12 * fmax(1.0, fabs(d->time))) {
        ctrl_logf(inst, CST_ERROR, "%s: communication point %.17g s is not the FMU's time %.17g s", fname, current, d->time);
        return CST_ERROR;
    }
    double end = current + h;
    /* bounded work: at most CTRL_MAX_SAMPLES_PER_STEP evaluations of the law in one DoStep */
    double due = floor((end - slack - sample_instant(d, d->next_sample)) / d->sample_time) + 1.0;
    if (!isfinite(end) || due > CTRL_MAX_SAMPLES_PER_STEP) {
        ctrl_logf(inst, CST_ERROR, "%s: a step of %g s covers %g samples of %g s; at most %d per step", fname, h, due,
                  d->sample_time, CTRL_MAX_SAMPLES_PER_STEP);
        return CST_ERROR;
    }
    /* Every sample instant before the end of the step (the one now included) is committed, with the inputs held over
     * the step. Invariant: the next sample instant is never more than the slack before the current time. */
    for (long n = 0; sample_instant(d, d->next_sample) <= end - slack; n++) {
        if (n >= CTRL_MAX_SAMPLES_PER_STEP) { /* sample instants that rounding cannot tell apart (huge times) */
            ctrl_logf(inst, CST_ERROR, "%s: more than %d samples in one step at t = %g s", fname, CTRL_MAX_SAMPLES_PER_STEP, end);
            return CST_ERROR;
        }
        if (commit(inst, fname) != CST_OK) {
            d->machine = CMS_ERROR;
            return CST_ERROR;
        }
    }
    d->time = end;
    return CST_OK;
}

/* ------------------------------------------------------------ FMU state */
CtrlStatus ctrl_check_state(CtrlInstance *inst, const void *blob, size_t size, const char *fname) {
    CtrlData d;
    if (blob == NULL || size != sizeof(CtrlData)) {
        ctrl_logf(inst, CST_ERROR, "%s: FMU state is NULL or has %zu bytes, expected %zu", fname, size, sizeof(CtrlData));
        return CST_ERROR;
    }
    memcpy(&d, blob, sizeof(d));
    int machine_ok = d.machine == CMS_INSTANTIATED || d.machine == CMS_INIT || d.machine == CMS_STEP || d.machine == CMS_TERMINATED;
    int ok = d.magic == CTRL_MAGIC && machine_ok && isfinite(d.time) && isfinite(d.start_time) && isfinite(d.sample_time) &&
             d.sample_time > 0.0 && d.next_sample >= 0 && (d.mode == 0 || d.mode == 1);
    for (int i = 0; ok && i < CTRL_NX; i++) ok = isfinite(d.x[i]);
    for (int i = 0; ok && i < CTRL_NU; i++) ok = isfinite(d.u[i]);
    if (!ok) {
        ctrl_logf(inst, CST_ERROR, "%s: not an FMU state of this controller (%s), or one with invalid fields", fname, CTRL_IDENTIFIER);
        return CST_ERROR;
    }
    return CST_OK;
}

int ctrl_is_state_block(const void *p) {
    unsigned long first;
    memcpy(&first, p, sizeof(first)); /* p points to at least a pointer's worth of memory either way */
    return first == CTRL_MAGIC;
}

CtrlStatus ctrl_restore(CtrlInstance *inst, const void *blob, const char *fname) {
    if (ctrl_check_state(inst, blob, sizeof(CtrlData), fname) != CST_OK) return CST_ERROR;
    memcpy(&inst->d, blob, sizeof(CtrlData)); /* restores the saved life-cycle state too, as the Reference FMUs */
    return CST_OK;
}
