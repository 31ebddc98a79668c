/* FMI 2.0 Co-Simulation layer of a pendulab controller FMU over ctrl_core. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ctrl_core.h"
#include "fmi2Functions.h"

typedef struct {
    CtrlInstance core;
    fmi2CallbackFunctions cb; /* copied: the importer's struct may not outlive the call */
} Fmi2Ctrl;

static void ctrl_log_fmi2(CtrlInstance *inst, CtrlStatus status, const char *category, const char *message) {
    Fmi2Ctrl *c = (Fmi2Ctrl *)inst;
    if (status < CST_WARNING && !inst->logging_on) return;
    if (c->cb.logger != NULL) c->cb.logger(c->cb.componentEnvironment, inst->name, (fmi2Status)status, category, "%s", message);
}

#define GET_INSTANCE(fname)                                                                                           \
    Fmi2Ctrl *c2 = (Fmi2Ctrl *)c;                                                                                     \
    if (c2 == NULL) return fmi2Error;                                                                                 \
    CtrlInstance *inst = &c2->core;                                                                                   \
    ctrl_logf(inst, CST_OK, "%s", fname)

static fmi2Status refuse(CtrlInstance *inst, const char *fname, const char *why) {
    ctrl_logf(inst, CST_ERROR, "%s: %s", fname, why);
    return fmi2Error;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    GET_INSTANCE("fmi2SetDebugLogging");
    if (nCategories > 0 && categories == NULL) return refuse(inst, "fmi2SetDebugLogging", "categories is NULL");
    for (size_t i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (cat == NULL || (strcmp(cat, "logStatusError") && strcmp(cat, "logStatusWarning") && strcmp(cat, "logCalls")))
            return refuse(inst, "fmi2SetDebugLogging", "unknown log category");
    }
    inst->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID, fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL) return NULL;
    Fmi2Ctrl tmp;
    memset(&tmp, 0, sizeof(tmp));
    tmp.cb = *functions;
    tmp.core.log = ctrl_log_fmi2;
    snprintf(tmp.core.name, sizeof(tmp.core.name), "%s", instanceName ? instanceName : "");
    if (instanceName == NULL || instanceName[0] == '\0') {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi2Instantiate: missing instance name");
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, CTRL_TOKEN) != 0) {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi2Instantiate: GUID %s does not match %s", fmuGUID ? fmuGUID : "(NULL)", CTRL_TOKEN);
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi2Instantiate: a controller FMU has Co-Simulation only, got fmuType %d", (int)fmuType);
        return NULL;
    }
    Fmi2Ctrl *c = (Fmi2Ctrl *)functions->allocateMemory(1, sizeof(Fmi2Ctrl));
    if (c == NULL) {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi2Instantiate: out of memory");
        return NULL;
    }
    memcpy(c, &tmp, sizeof(tmp));
    c->core.logging_on = loggingOn ? 1 : 0;
    ctrl_defaults(&c->core);
    return c;
}

void fmi2FreeInstance(fmi2Component c) {
    Fmi2Ctrl *c2 = (Fmi2Ctrl *)c;
    if (c2 != NULL) c2->cb.freeMemory(c2);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    GET_INSTANCE("fmi2SetupExperiment");
    if (ctrl_check(inst, CMS_INSTANTIATED, "fmi2SetupExperiment") != CST_OK) return fmi2Error;
    /* no solver: a tolerance does not apply, but a defined one must be valid (as for the plant FMUs) */
    if (ctrl_check_tolerance(inst, toleranceDefined, tolerance, "fmi2SetupExperiment") != CST_OK) return fmi2Error;
    if (!isfinite(startTime) || (stopTimeDefined && !(stopTime >= startTime)))
        return refuse(inst, "fmi2SetupExperiment", "start time must be finite and not after the stop time");
    inst->d.start_time = inst->d.time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    GET_INSTANCE("fmi2EnterInitializationMode");
    return (fmi2Status)ctrl_enter_initialization(inst, inst->d.start_time, "fmi2EnterInitializationMode");
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    GET_INSTANCE("fmi2ExitInitializationMode");
    return (fmi2Status)ctrl_exit_initialization(inst, "fmi2ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component c) {
    GET_INSTANCE("fmi2Terminate");
    if (ctrl_check(inst, CMS_STEP | CMS_ERROR, "fmi2Terminate") != CST_OK) return fmi2Error;
    inst->d.machine = CMS_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    GET_INSTANCE("fmi2Reset");
    ctrl_defaults(inst);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    GET_INSTANCE("fmi2GetReal");
    return (fmi2Status)ctrl_get_real(inst, "fmi2GetReal", vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    GET_INSTANCE("fmi2SetReal");
    return (fmi2Status)ctrl_set_real(inst, "fmi2SetReal", vr, nvr, value);
}

/* No Integer, Boolean or String variables: only empty requests succeed. */
#define NO_VARIABLES(fname, nvr)                                                                                      \
    if ((nvr) == 0) return fmi2OK;                                                                                    \
    return refuse(inst, fname, "the controller has no variables of this type")

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    GET_INSTANCE("fmi2GetInteger");
    (void)vr;
    (void)value;
    NO_VARIABLES("fmi2GetInteger", nvr);
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    GET_INSTANCE("fmi2GetBoolean");
    (void)vr;
    (void)value;
    NO_VARIABLES("fmi2GetBoolean", nvr);
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    GET_INSTANCE("fmi2GetString");
    (void)vr;
    (void)value;
    NO_VARIABLES("fmi2GetString", nvr);
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    GET_INSTANCE("fmi2SetInteger");
    (void)vr;
    (void)value;
    NO_VARIABLES("fmi2SetInteger", nvr);
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    GET_INSTANCE("fmi2SetBoolean");
    (void)vr;
    (void)value;
    NO_VARIABLES("fmi2SetBoolean", nvr);
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    GET_INSTANCE("fmi2SetString");
    (void)vr;
    (void)value;
    NO_VARIABLES("fmi2SetString", nvr);
}

/* ------------------------------------------------------------ FMU state */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    GET_INSTANCE("fmi2GetFMUstate");
    if (ctrl_check(inst, CMS_ANY & ~CMS_ERROR, "fmi2GetFMUstate") != CST_OK) return fmi2Error;
    if (FMUstate == NULL) return refuse(inst, "fmi2GetFMUstate", "FMUstate is NULL");
    if (*FMUstate == NULL) {
        *FMUstate = c2->cb.allocateMemory(1, sizeof(CtrlData));
        if (*FMUstate == NULL) return refuse(inst, "fmi2GetFMUstate", "out of memory");
    } else if (ctrl_check_state(inst, *FMUstate, sizeof(CtrlData), "fmi2GetFMUstate") != CST_OK) {
        return fmi2Error;
    }
    memcpy(*FMUstate, &inst->d, sizeof(CtrlData));
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    GET_INSTANCE("fmi2SetFMUstate");
    return (fmi2Status)ctrl_restore(inst, FMUstate, "fmi2SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    GET_INSTANCE("fmi2FreeFMUstate");
    if (FMUstate == NULL) return refuse(inst, "fmi2FreeFMUstate", "FMUstate is NULL");
    if (ctrl_is_state_block(FMUstate)) { /* the importer passed the state, not its address: free it, never crash */
        c2->cb.freeMemory(FMUstate);
        ctrl_logf(inst, CST_WARNING, "fmi2FreeFMUstate: got the FMU state itself instead of a pointer to it (importer bug); "
                  "the state was freed, the importer's variable still holds the freed address");
        return fmi2OK; /* as the plant FMUs: the call did what it was meant to */
    }
    if (*FMUstate != NULL) c2->cb.freeMemory(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    GET_INSTANCE("fmi2SerializedFMUstateSize");
    if (size == NULL) return refuse(inst, "fmi2SerializedFMUstateSize", "size is NULL");
    if (ctrl_check_state(inst, FMUstate, sizeof(CtrlData), "fmi2SerializedFMUstateSize") != CST_OK) return fmi2Error;
    *size = sizeof(CtrlData);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    GET_INSTANCE("fmi2SerializeFMUstate");
    if (ctrl_check_state(inst, FMUstate, sizeof(CtrlData), "fmi2SerializeFMUstate") != CST_OK) return fmi2Error;
    if (serializedState == NULL || size != sizeof(CtrlData)) return refuse(inst, "fmi2SerializeFMUstate", "bad buffer");
    memcpy(serializedState, FMUstate, sizeof(CtrlData));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate *FMUstate) {
    GET_INSTANCE("fmi2DeSerializeFMUstate");
    if (FMUstate == NULL) return refuse(inst, "fmi2DeSerializeFMUstate", "FMUstate is NULL");
    if (ctrl_check_state(inst, serializedState, size, "fmi2DeSerializeFMUstate") != CST_OK) return fmi2Error;
    if (*FMUstate == NULL) {
        *FMUstate = c2->cb.allocateMemory(1, sizeof(CtrlData));
        if (*FMUstate == NULL) return refuse(inst, "fmi2DeSerializeFMUstate", "out of memory");
    }
    memcpy(*FMUstate, serializedState, sizeof(CtrlData));
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    GET_INSTANCE("fmi2GetDirectionalDerivative");
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return refuse(inst, "fmi2GetDirectionalDerivative", "not supported (providesDirectionalDerivative = false)");
}

/* ------------------------------------------------------------ Co-Simulation */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    GET_INSTANCE("fmi2SetRealInputDerivatives");
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return refuse(inst, "fmi2SetRealInputDerivatives", "not supported (canInterpolateInputs = false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    GET_INSTANCE("fmi2GetRealOutputDerivatives");
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return refuse(inst, "fmi2GetRealOutputDerivatives", "not supported (maxOutputDerivativeOrder = 0)");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    GET_INSTANCE("fmi2DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    return (fmi2Status)ctrl_do_step(inst, currentCommunicationPoint, communicationStepSize, "fmi2DoStep");
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    GET_INSTANCE("fmi2CancelStep");
    return refuse(inst, "fmi2CancelStep", "DoStep never returns Pending");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    GET_INSTANCE("fmi2GetStatus");
    (void)s;
    (void)value;
    return refuse(inst, "fmi2GetStatus", "DoStep never returns Pending");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    GET_INSTANCE("fmi2GetRealStatus");
    if (value == NULL) return refuse(inst, "fmi2GetRealStatus", "value is NULL");
    if (s != fmi2LastSuccessfulTime) return refuse(inst, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is available");
    *value = inst->d.time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    GET_INSTANCE("fmi2GetIntegerStatus");
    (void)s;
    (void)value;
    return refuse(inst, "fmi2GetIntegerStatus", "no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    GET_INSTANCE("fmi2GetBooleanStatus");
    if (value == NULL) return refuse(inst, "fmi2GetBooleanStatus", "value is NULL");
    if (s != fmi2Terminated) return refuse(inst, "fmi2GetBooleanStatus", "only fmi2Terminated is available");
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    GET_INSTANCE("fmi2GetStringStatus");
    (void)s;
    (void)value;
    return refuse(inst, "fmi2GetStringStatus", "no string status");
}
