/* Model core shared by the FMI 2 and FMI 3 layers.
 *
 * Holds one instance's data (no global mutable state), implements the state
 * machine checks, value-reference access, the co-simulation step through the
 * solvers of ode_solver.h, directional derivatives and FMU-state copies. The
 * per-model constants come from the generated header model.h; this file and
 * fmu_core.c are the same for every model.
 */
#ifndef PENDULAB_FMU_CORE_H
#define PENDULAB_FMU_CORE_H

#include <stddef.h>

#include "model.h"
#include "ode_solver.h"

/* Work limit of one communication step: at most this many internal solver steps (about 0.2 s of CPU
 * for the elastic model); beyond it DoStep fails ("too many internal steps") and the instance enters
 * the Error state. Ample for co-simulation: 200 s of a stiff (k = 1e6 N/m) spring with dopri5. */
#define CORE_MAX_INTERNAL_STEPS 100000L
#define CORE_MAX_INTERNAL_STEPS_TEXT "100000 internal steps"

/* Communication steps whose span is below CORE_MIN_SOLVER_SPAN * max(1, |t|) (the solver's smallest
 * step, 1e-14 max(1, |t|) in ode_solver.c) are legal: DoStep advances time with one explicit Euler step
 * (its error is far below the rounding of the state) and returns OK; h = 1e-300 is such a step. */
#define CORE_MIN_SOLVER_SPAN 1e-14

/* Status codes: numerically equal to fmi2Status and fmi3Status. */
typedef enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 } CoreStatus;

/* Machine states, as bit flags so that each entry point lists where it is legal. */
typedef enum {
    MS_INSTANTIATED = 1 << 0,
    MS_INIT = 1 << 1,
    MS_STEP = 1 << 2,       /* co-simulation: step mode (FMI 2: stepComplete) */
    MS_EVENT = 1 << 3,      /* model exchange: event mode */
    MS_CONT = 1 << 4,       /* model exchange: continuous-time mode */
    MS_TERMINATED = 1 << 5,
    MS_ERROR = 1 << 6
} MachineState;

#define MS_ANY (MS_INSTANTIATED | MS_INIT | MS_STEP | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR)

typedef enum { KIND_NONE, KIND_TIME, KIND_STATE, KIND_DERIV, KIND_INPUT, KIND_OUTPUT, KIND_PARAM, KIND_TOL, KIND_HMAX, KIND_SOLVER, KIND_INDICATOR } VarKind;

/* Everything that defines the continuation of a simulation: copied verbatim for FMU states. */
typedef struct {
    unsigned long magic;
    int machine;
    double time;
    double x[MODEL_NX];
    double u[MODEL_NU];
    double p[MODEL_NP];
    double tolerance;      /* relative and absolute tolerance of the embedded solver */
    double max_step;       /* largest internal step [s]; 0: unlimited */
    int solver;            /* ODE_DOPRI5 or ODE_RODAS4 */
    int tolerance_from_master;
    OdeSolver ode;
} CoreData;

struct Instance;
typedef void (*core_log_fn)(struct Instance *inst, CoreStatus status, const char *category, const char *message);

typedef struct Instance {
    CoreData d;
    int is_cosim;
    int logging_on;
    int terminate_requested; /* a spring reached its limit in DoStep: the FMU asked the master to stop */
    int event_mode_used;     /* FMI 3 CS with eventModeUsed (flip events): DoStep stops at a flip */
    int early_return;        /* the importer allows DoStep to end before its end point */
    int event_pending;       /* the last DoStep found a flip: eventHandlingNeeded */
    core_log_fn log;
    void *env;             /* importer's environment pointer */
    const void *callbacks; /* FMI 2: the fmi2CallbackFunctions pointer */
    void *logger;          /* FMI 3: the log message callback */
    char name[256];
    /* CasADi work arrays */
    double w[MODEL_SZ_W > 0 ? MODEL_SZ_W : 1];
    casadi_int iw[MODEL_SZ_IW > 0 ? MODEL_SZ_IW : 1];
    const double *arg[MODEL_SZ_ARG > 0 ? MODEL_SZ_ARG : 1];
    double *res[MODEL_SZ_RES > 0 ? MODEL_SZ_RES : 1];
} Instance;

void core_defaults(Instance *inst);
void core_logf(Instance *inst, CoreStatus status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
void core_debugf(Instance *inst, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Return ST_OK when inst->d.machine is in `allowed`, else log and return ST_ERROR. */
CoreStatus core_check(Instance *inst, int allowed, const char *fname);
const char *core_machine_name(int machine);

VarKind core_classify(unsigned int vr, int *index);
CoreStatus core_get_real(Instance *inst, const char *fname, const unsigned int *vr, size_t n, double *value);
CoreStatus core_set_real(Instance *inst, const char *fname, const unsigned int *vr, size_t n, const double *value);
CoreStatus core_get_int(Instance *inst, const char *fname, const unsigned int *vr, size_t n, int *value);
CoreStatus core_set_int(Instance *inst, const char *fname, const unsigned int *vr, size_t n, const int *value);

CoreStatus core_set_experiment(Instance *inst, int tolerance_defined, double tolerance, double start_time);
CoreStatus core_exit_initialization(Instance *inst);
CoreStatus core_do_step(Instance *inst, double current, double h);

CoreStatus core_derivatives(Instance *inst, double *xdot);
CoreStatus core_set_states(Instance *inst, const double *x, size_t n);
CoreStatus core_set_time(Instance *inst, double t);

/* Events (the elastic model; the rigid model has none): MODEL_NZ event indicators, the spring margins
 * z_i = r_i - MODEL_SPRING_LIMIT * L_i. The model is singular at r = 0, so a margin reaching 0 ends the
 * simulation: Model Exchange requests terminateSimulation at the event (NewDiscreteStates /
 * UpdateDiscreteStates, CompletedIntegratorStep); Co-Simulation ends the step at the last of
 * CORE_EVENT_SUBSTEPS equal sub-steps before the limit and returns ST_DISCARD with
 * inst->terminate_requested set (FMI 2: Discard + fmi2Terminated status; FMI 3: terminateSimulation). */
#define CORE_EVENT_SUBSTEPS 64
/* FMI 3 CS event mode (flip events, eventModeUsed): after a successful step, a flip indicator that changed
 * sign is located by bisection (re-integrating from the step's start, to CORE_EVENT_TIME_RTOL max(1, |t|));
 * with early return allowed the step ends just past the flip, else at its end point, and event_pending is
 * set (eventHandlingNeeded). */
#define CORE_EVENT_TIME_RTOL 1e-12
CoreStatus core_event_indicators(Instance *inst, double *z, size_t n, const char *fname);
/* 1 (with a log line) when a spring margin is <= 0 at the current state, else 0. */
int core_spring_event(Instance *inst, const char *fname);
CoreStatus core_directional(Instance *inst, const unsigned int *unknown, size_t n_unknown, const unsigned int *known,
                            size_t n_known, const double *seed, double *sensitivity);

/* FMU state: the layer allocates sizeof(CoreData) bytes; the serialized form is those bytes.
 * core_check_state_blob checks size and model magic and then every field with the setters' rules
 * (finite time, finite states, finite inputs, parameters with their sign
 * rules, tolerance in (0, 1), max_step >= 0, solver 0/1, a solver block that is unset or consistent);
 * a rejected state logs why and changes nothing. core_restore resumes the life-cycle state stored
 * with the FMU state (as the Reference FMUs do: instantiate -> restore -> step, and restart after an
 * error); a state of the other interface (ME modes into CS or back) is refused. */
CoreStatus core_check_state_blob(Instance *inst, const void *blob, size_t size, const char *fname);
CoreStatus core_restore(Instance *inst, const CoreData *saved, const char *fname);

/* 1 when the memory at p starts with this model's magic number, i.e. p is an FMU state itself and not the
 * address of the importer's variable that holds one. FreeFMUState(instance, state) instead of
 * FreeFMUState(instance, &state) is a known importer bug (fmusim 0.0.39 after (de)serializing a state
 * file); the layers then free the state, log a warning and return OK instead of crashing. */
int core_is_state_block(const void *p);

#endif
