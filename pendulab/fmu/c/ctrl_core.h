/* Core of a pendulab controller FMU (Co-Simulation only), shared by its FMI 2 and FMI 3 layers.
 *
 * A sampled-data controller: the inputs are the measured plant state, the outputs the torques, held
 * constant between the samples t0 + k h (h: parameter sample_time). At a sample instant the outputs
 * are the control law at the current inputs (direct feedthrough: a master sets the state, then reads
 * the torques); leaving the instant (DoStep) commits that sample (the held torques and the mode of a
 * switching controller). Sample instants strictly inside a communication step use the inputs held over
 * the step. One instance's data lives in CtrlData (no global mutable state); FMU states are copies of it.
 * The per-controller constants and the CasADi-generated law come from the generated controller.h.
 */
#ifndef PENDULAB_CTRL_CORE_H
#define PENDULAB_CTRL_CORE_H

#include <stddef.h>

#include "controller.h"

typedef enum { CST_OK = 0, CST_WARNING = 1, CST_DISCARD = 2, CST_ERROR = 3, CST_FATAL = 4 } CtrlStatus;

typedef enum {
    CMS_INSTANTIATED = 1 << 0,
    CMS_INIT = 1 << 1,
    CMS_STEP = 1 << 2,
    CMS_TERMINATED = 1 << 3,
    CMS_ERROR = 1 << 4
} CtrlMachine;

#define CMS_ANY (CMS_INSTANTIATED | CMS_INIT | CMS_STEP | CMS_TERMINATED | CMS_ERROR)

/* A time within CTRL_SAMPLE_SLACK sample periods of a sample instant is that instant (masters accumulate
 * time in floating point); the same slack as pendulab's TVLQR tracker uses for its sample index. */
#define CTRL_SAMPLE_SLACK 1e-6

/* Work limit of one DoStep: at most this many samples (evaluations of the control law); a longer step is an
 * Error (the instance stays usable) instead of an unbounded loop. */
#define CTRL_MAX_SAMPLES_PER_STEP 1000000

typedef struct {
    unsigned long magic;
    int machine;
    double time;          /* current communication point [s] */
    double start_time;    /* t0 [s] */
    double sample_time;   /* h [s] */
    long next_sample;     /* index k of the next sample not yet committed */
    int mode;             /* switching controllers: 0 = first law (pump / track), 1 = balance */
    double x[CTRL_NX];    /* inputs: the measured state */
    double u[CTRL_NU];    /* held outputs [N.m] */
} CtrlData;

struct CtrlInstance;
typedef void (*ctrl_log_fn)(struct CtrlInstance *inst, CtrlStatus status, const char *category, const char *message);

typedef struct CtrlInstance {
    CtrlData d;
    int logging_on;
    ctrl_log_fn log;
    void *env;
    char name[256];
    double w[CTRL_SZ_W > 0 ? CTRL_SZ_W : 1];
    casadi_int iw[CTRL_SZ_IW > 0 ? CTRL_SZ_IW : 1];
    const double *arg[CTRL_SZ_ARG > 0 ? CTRL_SZ_ARG : 1];
    double *res[CTRL_SZ_RES > 0 ? CTRL_SZ_RES : 1];
} CtrlInstance;

void ctrl_defaults(CtrlInstance *inst);
void ctrl_logf(CtrlInstance *inst, CtrlStatus status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
CtrlStatus ctrl_check(CtrlInstance *inst, int allowed, const char *fname);
CtrlStatus ctrl_get_real(CtrlInstance *inst, const char *fname, const unsigned int *vr, size_t n, double *value);
CtrlStatus ctrl_set_real(CtrlInstance *inst, const char *fname, const unsigned int *vr, size_t n, const double *value);
/* A tolerance the master defined (toleranceDefined) must be in (0, 1), as for the plant FMUs; unused otherwise. */
CtrlStatus ctrl_check_tolerance(CtrlInstance *inst, int defined, double tolerance, const char *fname);
CtrlStatus ctrl_enter_initialization(CtrlInstance *inst, double start_time, const char *fname);
CtrlStatus ctrl_exit_initialization(CtrlInstance *inst, const char *fname);
CtrlStatus ctrl_do_step(CtrlInstance *inst, double current, double h, const char *fname);
/* FMU state = the bytes of CtrlData; checked (size, magic, every field) before use; a rejected state changes nothing. */
CtrlStatus ctrl_check_state(CtrlInstance *inst, const void *blob, size_t size, const char *fname);
CtrlStatus ctrl_restore(CtrlInstance *inst, const void *blob, const char *fname);
/* Does p point to an FMU state (its magic) rather than to a pointer to one? FreeFMUState with the state itself
 * (an importer bug) is then freed instead of dereferenced, as in the plant FMUs. */
int ctrl_is_state_block(const void *p);

#endif
