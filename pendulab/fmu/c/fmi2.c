/* FMI 2.0 layer (Co-Simulation and Model Exchange) over the model core. */
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_core.h"

typedef struct {
    Instance core;
    fmi2CallbackFunctions cb; /* copied: the importer's struct may not outlive the call */
} Fmi2Instance;

static void fmi2_log(Instance *inst, CoreStatus status, const char *category, const char *message) {
    Fmi2Instance *c = (Fmi2Instance *)inst;
    if (c->cb.logger != NULL) c->cb.logger(c->cb.componentEnvironment, inst->name, (fmi2Status)status, category, "%s", message);
}

/* Every entry point starts with this: a NULL instance is reported as an error, never dereferenced. */
#define GET_INSTANCE(fname)                                                                                           \
    Fmi2Instance *c2 = (Fmi2Instance *)c;                                                                             \
    if (c2 == NULL) return fmi2Error;                                                                                 \
    Instance *inst = &c2->core;                                                                                       \
    core_debugf(inst, "%s", fname)

#define CHECK_STATE(allowed, fname)                                                                                   \
    if (core_check(inst, (allowed), (fname)) != ST_OK) return fmi2Error

/* A failed call of a step or evaluation puts the instance into the error state. */
static fmi2Status fail(Instance *inst, CoreStatus s) {
    if (s >= ST_ERROR) inst->d.machine = MS_ERROR;
    return (fmi2Status)s;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    GET_INSTANCE("fmi2SetDebugLogging");
    if (nCategories > 0 && categories == NULL) {
        core_logf(inst, ST_ERROR, "fmi2SetDebugLogging: categories is NULL with nCategories = %zu", nCategories);
        return fmi2Error;
    }
    for (size_t i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (cat == NULL || (strcmp(cat, "logStatusError") && strcmp(cat, "logStatusWarning") && strcmp(cat, "logCalls"))) {
            core_logf(inst, ST_ERROR, "fmi2SetDebugLogging: unknown log category %s", cat ? cat : "(NULL)");
            return fmi2Error;
        }
    }
    inst->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID, fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL) return NULL;
    Fmi2Instance tmp; /* for logging before allocation succeeds */
    memset(&tmp, 0, sizeof(tmp));
    tmp.cb = *functions;
    tmp.core.log = fmi2_log;
    snprintf(tmp.core.name, sizeof(tmp.core.name), "%s", instanceName ? instanceName : "");
    if (instanceName == NULL || instanceName[0] == '\0') {
        core_logf(&tmp.core, ST_ERROR, "fmi2Instantiate: missing instance name");
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_TOKEN) != 0) {
        core_logf(&tmp.core, ST_ERROR, "fmi2Instantiate: GUID %s does not match %s", fmuGUID ? fmuGUID : "(NULL)", MODEL_TOKEN);
        return NULL;
    }
    if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange) {
        core_logf(&tmp.core, ST_ERROR, "fmi2Instantiate: unknown fmuType %d", (int)fmuType);
        return NULL;
    }
    Fmi2Instance *c = (Fmi2Instance *)functions->allocateMemory(1, sizeof(Fmi2Instance));
    if (c == NULL) {
        core_logf(&tmp.core, ST_ERROR, "fmi2Instantiate: out of memory");
        return NULL;
    }
    memcpy(c, &tmp, sizeof(tmp));
    c->core.is_cosim = fmuType == fmi2CoSimulation;
    c->core.logging_on = loggingOn ? 1 : 0;
    core_defaults(&c->core);
    return c;
}

void fmi2FreeInstance(fmi2Component c) {
    Fmi2Instance *c2 = (Fmi2Instance *)c;
    if (c2 == NULL) return;
    c2->cb.freeMemory(c2);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    GET_INSTANCE("fmi2SetupExperiment");
    CHECK_STATE(MS_INSTANTIATED, "fmi2SetupExperiment");
    if (stopTimeDefined && !(stopTime >= startTime)) {
        core_logf(inst, ST_ERROR, "fmi2SetupExperiment: stop time %g before start time %g", stopTime, startTime);
        return fmi2Error;
    }
    return (fmi2Status)core_set_experiment(inst, toleranceDefined != 0, tolerance, startTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    GET_INSTANCE("fmi2EnterInitializationMode");
    CHECK_STATE(MS_INSTANTIATED, "fmi2EnterInitializationMode");
    inst->d.machine = MS_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    GET_INSTANCE("fmi2ExitInitializationMode");
    CHECK_STATE(MS_INIT, "fmi2ExitInitializationMode");
    CoreStatus s = core_exit_initialization(inst);
    if (s != ST_OK) return fail(inst, s);
    inst->d.machine = inst->is_cosim ? MS_STEP : MS_EVENT;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    GET_INSTANCE("fmi2Terminate");
    CHECK_STATE(MS_STEP | MS_EVENT | MS_CONT, "fmi2Terminate");
    inst->d.machine = MS_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    GET_INSTANCE("fmi2Reset");
    CHECK_STATE(MS_ANY, "fmi2Reset");
    core_defaults(inst);
    return fmi2OK;
}

/* ------------------------------------------------------------ variables */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    GET_INSTANCE("fmi2GetReal");
    return (fmi2Status)core_get_real(inst, "fmi2GetReal", vr, nvr, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    GET_INSTANCE("fmi2GetInteger");
    return (fmi2Status)core_get_int(inst, "fmi2GetInteger", vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    GET_INSTANCE("fmi2SetReal");
    return (fmi2Status)core_set_real(inst, "fmi2SetReal", vr, nvr, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    GET_INSTANCE("fmi2SetInteger");
    return (fmi2Status)core_set_int(inst, "fmi2SetInteger", vr, nvr, value);
}

static fmi2Status no_such_variable(Instance *inst, const char *fname, size_t nvr) {
    if (nvr == 0) return fmi2OK;
    core_logf(inst, ST_ERROR, "%s: this model has no variables of that type", fname);
    return fmi2Error;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    GET_INSTANCE("fmi2GetBoolean");
    (void)vr;
    (void)value;
    return no_such_variable(inst, "fmi2GetBoolean", nvr);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    GET_INSTANCE("fmi2GetString");
    (void)vr;
    (void)value;
    return no_such_variable(inst, "fmi2GetString", nvr);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    GET_INSTANCE("fmi2SetBoolean");
    (void)vr;
    (void)value;
    return no_such_variable(inst, "fmi2SetBoolean", nvr);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    GET_INSTANCE("fmi2SetString");
    (void)vr;
    (void)value;
    return no_such_variable(inst, "fmi2SetString", nvr);
}

/* ------------------------------------------------------------ FMU state */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    GET_INSTANCE("fmi2GetFMUstate");
    CHECK_STATE(MS_ANY & ~MS_ERROR, "fmi2GetFMUstate");
    if (FMUstate == NULL) {
        core_logf(inst, ST_ERROR, "fmi2GetFMUstate: FMUstate is NULL");
        return fmi2Error;
    }
    if (*FMUstate == NULL) {
        *FMUstate = c2->cb.allocateMemory(1, sizeof(CoreData));
        if (*FMUstate == NULL) {
            core_logf(inst, ST_ERROR, "fmi2GetFMUstate: out of memory");
            return fmi2Error;
        }
    } else if (core_check_state_blob(inst, *FMUstate, sizeof(CoreData), "fmi2GetFMUstate") != ST_OK) {
        return fmi2Error;
    }
    memcpy(*FMUstate, &inst->d, sizeof(CoreData));
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    GET_INSTANCE("fmi2SetFMUstate");
    CHECK_STATE(MS_ANY, "fmi2SetFMUstate"); /* also in Error: restart from a stored state */
    return (fmi2Status)core_restore(inst, (const CoreData *)FMUstate, "fmi2SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    GET_INSTANCE("fmi2FreeFMUstate");
    if (FMUstate == NULL) {
        core_logf(inst, ST_ERROR, "fmi2FreeFMUstate: FMUstate is NULL");
        return fmi2Error;
    }
    if (core_is_state_block(FMUstate)) { /* the importer passed the state, not its address: free it, never crash */
        c2->cb.freeMemory(FMUstate);
        core_logf(inst, ST_WARNING, "fmi2FreeFMUstate: got the FMU state itself instead of a pointer to it (importer "
                  "bug); the state was freed, the importer's variable still holds the freed address");
        return fmi2OK; /* the call did what it was meant to; importers abort on Warning (fmusim 0.0.39) */
    }
    if (*FMUstate != NULL) c2->cb.freeMemory(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    GET_INSTANCE("fmi2SerializedFMUstateSize");
    if (size == NULL || core_check_state_blob(inst, FMUstate, sizeof(CoreData), "fmi2SerializedFMUstateSize") != ST_OK) {
        if (size == NULL) core_logf(inst, ST_ERROR, "fmi2SerializedFMUstateSize: size is NULL");
        return fmi2Error;
    }
    *size = sizeof(CoreData);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    GET_INSTANCE("fmi2SerializeFMUstate");
    if (core_check_state_blob(inst, FMUstate, sizeof(CoreData), "fmi2SerializeFMUstate") != ST_OK) return fmi2Error;
    if (serializedState == NULL || size != sizeof(CoreData)) {
        core_logf(inst, ST_ERROR, "fmi2SerializeFMUstate: buffer is NULL or has %zu bytes, expected %zu", size,
                  sizeof(CoreData));
        return fmi2Error;
    }
    memcpy(serializedState, FMUstate, sizeof(CoreData));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate *FMUstate) {
    GET_INSTANCE("fmi2DeSerializeFMUstate");
    if (FMUstate == NULL) {
        core_logf(inst, ST_ERROR, "fmi2DeSerializeFMUstate: FMUstate is NULL");
        return fmi2Error;
    }
    if (core_check_state_blob(inst, serializedState, size, "fmi2DeSerializeFMUstate") != ST_OK) return fmi2Error;
    if (*FMUstate == NULL) {
        *FMUstate = c2->cb.allocateMemory(1, sizeof(CoreData));
        if (*FMUstate == NULL) {
            core_logf(inst, ST_ERROR, "fmi2DeSerializeFMUstate: out of memory");
            return fmi2Error;
        }
    }
    memcpy(*FMUstate, serializedState, sizeof(CoreData));
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    GET_INSTANCE("fmi2GetDirectionalDerivative");
    CHECK_STATE(MS_INIT | MS_STEP | MS_EVENT | MS_CONT | MS_TERMINATED, "fmi2GetDirectionalDerivative");
    return (fmi2Status)core_directional(inst, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown, dvUnknown);
}

/* ------------------------------------------------------------ Model Exchange */
#define ME_ONLY(fname)                                                                                                \
    if (inst->is_cosim) {                                                                                             \
        core_logf(inst, ST_ERROR, "%s: only available for Model Exchange", fname);                                    \
        return fmi2Error;                                                                                             \
    }

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    GET_INSTANCE("fmi2EnterEventMode");
    ME_ONLY("fmi2EnterEventMode");
    CHECK_STATE(MS_EVENT | MS_CONT, "fmi2EnterEventMode");
    inst->d.machine = MS_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    GET_INSTANCE("fmi2NewDiscreteStates");
    ME_ONLY("fmi2NewDiscreteStates");
    CHECK_STATE(MS_EVENT, "fmi2NewDiscreteStates");
    if (eventInfo == NULL) {
        core_logf(inst, ST_ERROR, "fmi2NewDiscreteStates: eventInfo is NULL");
        return fmi2Error;
    }
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = core_spring_event(inst, "fmi2NewDiscreteStates") ? fmi2True : fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    GET_INSTANCE("fmi2EnterContinuousTimeMode");
    ME_ONLY("fmi2EnterContinuousTimeMode");
    CHECK_STATE(MS_EVENT, "fmi2EnterContinuousTimeMode");
    inst->d.machine = MS_CONT;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    GET_INSTANCE("fmi2CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    ME_ONLY("fmi2CompletedIntegratorStep");
    CHECK_STATE(MS_CONT, "fmi2CompletedIntegratorStep");
    if (enterEventMode == NULL || terminateSimulation == NULL) {
        core_logf(inst, ST_ERROR, "fmi2CompletedIntegratorStep: NULL output argument");
        return fmi2Error;
    }
    *enterEventMode = fmi2False;
    *terminateSimulation = core_spring_event(inst, "fmi2CompletedIntegratorStep") ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    GET_INSTANCE("fmi2SetTime");
    ME_ONLY("fmi2SetTime");
    CHECK_STATE(MS_EVENT | MS_CONT, "fmi2SetTime");
    return (fmi2Status)core_set_time(inst, time);
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    GET_INSTANCE("fmi2SetContinuousStates");
    ME_ONLY("fmi2SetContinuousStates");
    CHECK_STATE(MS_CONT, "fmi2SetContinuousStates");
    return (fmi2Status)core_set_states(inst, x, nx);
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    GET_INSTANCE("fmi2GetDerivatives");
    ME_ONLY("fmi2GetDerivatives");
    CHECK_STATE(MS_INIT | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR, "fmi2GetDerivatives");
    if (derivatives == NULL || nx != MODEL_NX) {
        core_logf(inst, ST_ERROR, "fmi2GetDerivatives: expected a non-NULL array of %d, got n = %zu", MODEL_NX, nx);
        return fmi2Error;
    }
    return (fmi2Status)core_derivatives(inst, derivatives);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    GET_INSTANCE("fmi2GetEventIndicators");
    ME_ONLY("fmi2GetEventIndicators");
    CHECK_STATE(MS_INIT | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR, "fmi2GetEventIndicators");
    return (fmi2Status)core_event_indicators(inst, eventIndicators, ni, "fmi2GetEventIndicators");
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    GET_INSTANCE("fmi2GetContinuousStates");
    ME_ONLY("fmi2GetContinuousStates");
    CHECK_STATE(MS_INIT | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR, "fmi2GetContinuousStates");
    if (x == NULL || nx != MODEL_NX) {
        core_logf(inst, ST_ERROR, "fmi2GetContinuousStates: expected a non-NULL array of %d, got n = %zu", MODEL_NX, nx);
        return fmi2Error;
    }
    memcpy(x, inst->d.x, sizeof(inst->d.x));
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    GET_INSTANCE("fmi2GetNominalsOfContinuousStates");
    ME_ONLY("fmi2GetNominalsOfContinuousStates");
    CHECK_STATE(MS_INSTANTIATED | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR, "fmi2GetNominalsOfContinuousStates");
    if (x_nominal == NULL || nx != MODEL_NX) {
        core_logf(inst, ST_ERROR, "fmi2GetNominalsOfContinuousStates: expected a non-NULL array of %d, got n = %zu",
                  MODEL_NX, nx);
        return fmi2Error;
    }
    for (int i = 0; i < MODEL_NX; i++) x_nominal[i] = 1.0;
    return fmi2OK;
}

/* ------------------------------------------------------------ Co-Simulation */
#define CS_ONLY(fname)                                                                                                \
    if (!inst->is_cosim) {                                                                                            \
        core_logf(inst, ST_ERROR, "%s: only available for Co-Simulation", fname);                                     \
        return fmi2Error;                                                                                             \
    }

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    GET_INSTANCE("fmi2SetRealInputDerivatives");
    (void)vr;
    (void)order;
    (void)value;
    CS_ONLY("fmi2SetRealInputDerivatives");
    core_logf(inst, ST_ERROR, "fmi2SetRealInputDerivatives: not supported (canInterpolateInputs = false), nvr = %zu", nvr);
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    GET_INSTANCE("fmi2GetRealOutputDerivatives");
    (void)vr;
    (void)order;
    (void)value;
    CS_ONLY("fmi2GetRealOutputDerivatives");
    core_logf(inst, ST_ERROR, "fmi2GetRealOutputDerivatives: not supported (maxOutputDerivativeOrder = 0), nvr = %zu", nvr);
    return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    GET_INSTANCE("fmi2DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    CS_ONLY("fmi2DoStep");
    CHECK_STATE(MS_STEP, "fmi2DoStep");
    return (fmi2Status)core_do_step(inst, currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    GET_INSTANCE("fmi2CancelStep");
    CS_ONLY("fmi2CancelStep");
    core_logf(inst, ST_ERROR, "fmi2CancelStep: steps complete synchronously; nothing to cancel");
    return fmi2Error;
}

static fmi2Status no_status(Instance *inst, const char *fname, const void *value) {
    (void)value;
    core_logf(inst, ST_DISCARD, "%s: no asynchronous status (steps complete synchronously)", fname);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    GET_INSTANCE("fmi2GetStatus");
    (void)s;
    return no_status(inst, "fmi2GetStatus", value);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    GET_INSTANCE("fmi2GetRealStatus");
    CS_ONLY("fmi2GetRealStatus");
    if (s == fmi2LastSuccessfulTime && value != NULL) {
        *value = inst->d.time;
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetRealStatus", value);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    GET_INSTANCE("fmi2GetIntegerStatus");
    (void)s;
    return no_status(inst, "fmi2GetIntegerStatus", value);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    GET_INSTANCE("fmi2GetBooleanStatus");
    if (s == fmi2Terminated && value != NULL && inst->is_cosim) { /* after a Discard: did the FMU end the run? */
        *value = inst->terminate_requested ? fmi2True : fmi2False;
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetBooleanStatus", value);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    GET_INSTANCE("fmi2GetStringStatus");
    (void)s;
    return no_status(inst, "fmi2GetStringStatus", value);
}
