/* FMI 3.0 Co-Simulation layer of a pendulab controller FMU over ctrl_core. Model Exchange, Scheduled
 * Execution, clocks, event mode and derivatives are refused with a logged error (the controller is a
 * sampled-data Co-Simulation FMU); every entry point checks its instance and arguments. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctrl_core.h"
#include "fmi3Functions.h"

typedef struct {
    CtrlInstance core;
    fmi3LogMessageCallback logMessage;
} Fmi3Ctrl;

static void ctrl_log_fmi3(CtrlInstance *inst, CtrlStatus status, const char *category, const char *message) {
    Fmi3Ctrl *c = (Fmi3Ctrl *)inst;
    if (status < CST_WARNING && !inst->logging_on) return;
    if (c->logMessage != NULL) c->logMessage(inst->env, (fmi3Status)status, category, message);
}

#define GET_INSTANCE(fname)                                                                                           \
    Fmi3Ctrl *c3 = (Fmi3Ctrl *)instance;                                                                              \
    if (c3 == NULL) return fmi3Error;                                                                                 \
    CtrlInstance *inst = &c3->core;                                                                                   \
    ctrl_logf(inst, CST_OK, "%s", fname)

static fmi3Status refuse(CtrlInstance *inst, const char *fname, const char *why) {
    ctrl_logf(inst, CST_ERROR, "%s: %s", fname, why);
    return fmi3Error;
}

static fmi3Status no_variables(CtrlInstance *inst, const char *fname, size_t n) {
    if (n == 0) return fmi3OK;
    return refuse(inst, fname, "the controller has no variables of this type");
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories, const fmi3String categories[]) {
    GET_INSTANCE("fmi3SetDebugLogging");
    if (nCategories > 0 && categories == NULL) return refuse(inst, "fmi3SetDebugLogging", "categories is NULL");
    for (size_t i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (cat == NULL || (strcmp(cat, "logStatusError") && strcmp(cat, "logStatusWarning") && strcmp(cat, "logCalls")))
            return refuse(inst, "fmi3SetDebugLogging", "unknown log category");
    }
    inst->logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                          fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    if (logMessage != NULL)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError", "a controller FMU has Co-Simulation only (no Model Exchange)");
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                         fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath;
    (void)visible;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    Fmi3Ctrl tmp;
    memset(&tmp, 0, sizeof(tmp));
    tmp.logMessage = logMessage;
    tmp.core.log = ctrl_log_fmi3;
    tmp.core.env = instanceEnvironment;
    snprintf(tmp.core.name, sizeof(tmp.core.name), "%s", instanceName ? instanceName : "");
    if (instanceName == NULL || instanceName[0] == '\0') {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi3InstantiateCoSimulation: missing instance name");
        return NULL;
    }
    if (instantiationToken == NULL || strcmp(instantiationToken, CTRL_TOKEN) != 0) {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi3InstantiateCoSimulation: instantiation token %s does not match %s",
                  instantiationToken ? instantiationToken : "(NULL)", CTRL_TOKEN);
        return NULL;
    }
    if (eventModeUsed) {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi3InstantiateCoSimulation: eventModeUsed is not supported (hasEventMode = false)");
        return NULL;
    }
    Fmi3Ctrl *c = (Fmi3Ctrl *)calloc(1, sizeof(Fmi3Ctrl));
    if (c == NULL) {
        ctrl_logf(&tmp.core, CST_ERROR, "fmi3InstantiateCoSimulation: out of memory");
        return NULL;
    }
    memcpy(c, &tmp, sizeof(tmp));
    c->core.logging_on = loggingOn ? 1 : 0;
    ctrl_defaults(&c->core);
    return c;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                               fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    if (logMessage != NULL)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError", "Scheduled Execution is not supported by this FMU");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    GET_INSTANCE("fmi3EnterInitializationMode");
    if (ctrl_check(inst, CMS_INSTANTIATED, "fmi3EnterInitializationMode") != CST_OK) return fmi3Error;
    /* no solver: a tolerance does not apply, but a defined one must be valid (as for the plant FMUs) */
    if (ctrl_check_tolerance(inst, toleranceDefined, tolerance, "fmi3EnterInitializationMode") != CST_OK) return fmi3Error;
    if (stopTimeDefined && !(stopTime >= startTime)) return refuse(inst, "fmi3EnterInitializationMode", "stop time before start time");
    return (fmi3Status)ctrl_enter_initialization(inst, startTime, "fmi3EnterInitializationMode");
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3ExitInitializationMode");
    return (fmi3Status)ctrl_exit_initialization(inst, "fmi3ExitInitializationMode");
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3EnterEventMode");
    return refuse(inst, "fmi3EnterEventMode", "not supported (no event mode)");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    GET_INSTANCE("fmi3Terminate");
    if (ctrl_check(inst, CMS_STEP | CMS_ERROR, "fmi3Terminate") != CST_OK) return fmi3Error;
    inst->d.machine = CMS_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    GET_INSTANCE("fmi3Reset");
    ctrl_defaults(inst);
    return fmi3OK;
}

/* ------------------------------------------------------------ variables */
fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    GET_INSTANCE("fmi3GetFloat64");
    if (nValues != nValueReferences) return refuse(inst, "fmi3GetFloat64", "nValues must equal nValueReferences (scalars only)");
    return (fmi3Status)ctrl_get_real(inst, "fmi3GetFloat64", valueReferences, nValueReferences, values);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    GET_INSTANCE("fmi3SetFloat64");
    if (nValues != nValueReferences) return refuse(inst, "fmi3SetFloat64", "nValues must equal nValueReferences (scalars only)");
    return (fmi3Status)ctrl_set_real(inst, "fmi3SetFloat64", valueReferences, nValueReferences, values);
}

#define NO_GETTER(Name, Type)                                                                                          \
    fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                             Type values[], size_t nValues) {                                                          \
        GET_INSTANCE("fmi3Get" #Name);                                                                                 \
        (void)valueReferences;                                                                                         \
        (void)values;                                                                                                  \
        (void)nValues;                                                                                                 \
        return no_variables(inst, "fmi3Get" #Name, nValueReferences);                                                  \
    }
#define NO_SETTER(Name, Type)                                                                                          \
    fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                             const Type values[], size_t nValues) {                                                    \
        GET_INSTANCE("fmi3Set" #Name);                                                                                 \
        (void)valueReferences;                                                                                         \
        (void)values;                                                                                                  \
        (void)nValues;                                                                                                 \
        return no_variables(inst, "fmi3Set" #Name, nValueReferences);                                                  \
    }

NO_GETTER(Float32, fmi3Float32)
NO_GETTER(Int8, fmi3Int8)
NO_GETTER(UInt8, fmi3UInt8)
NO_GETTER(Int16, fmi3Int16)
NO_GETTER(UInt16, fmi3UInt16)
NO_GETTER(Int32, fmi3Int32)
NO_GETTER(UInt32, fmi3UInt32)
NO_GETTER(Int64, fmi3Int64)
NO_GETTER(UInt64, fmi3UInt64)
NO_GETTER(Boolean, fmi3Boolean)
NO_GETTER(String, fmi3String)
NO_SETTER(Float32, fmi3Float32)
NO_SETTER(Int8, fmi3Int8)
NO_SETTER(UInt8, fmi3UInt8)
NO_SETTER(Int16, fmi3Int16)
NO_SETTER(UInt16, fmi3UInt16)
NO_SETTER(Int32, fmi3Int32)
NO_SETTER(UInt32, fmi3UInt32)
NO_SETTER(Int64, fmi3Int64)
NO_SETTER(UInt64, fmi3UInt64)
NO_SETTER(Boolean, fmi3Boolean)
NO_SETTER(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    GET_INSTANCE("fmi3GetBinary");
    (void)valueReferences;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_variables(inst, "fmi3GetBinary", nValueReferences);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    GET_INSTANCE("fmi3SetBinary");
    (void)valueReferences;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_variables(inst, "fmi3SetBinary", nValueReferences);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[]) {
    GET_INSTANCE("fmi3GetClock");
    (void)valueReferences;
    (void)values;
    return no_variables(inst, "fmi3GetClock", nValueReferences);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[]) {
    GET_INSTANCE("fmi3SetClock");
    (void)valueReferences;
    (void)values;
    return no_variables(inst, "fmi3SetClock", nValueReferences);
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    GET_INSTANCE("fmi3GetIntervalDecimal");
    (void)valueReferences;
    (void)intervals;
    (void)qualifiers;
    return no_variables(inst, "fmi3GetIntervalDecimal", nValueReferences);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    GET_INSTANCE("fmi3GetIntervalFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return no_variables(inst, "fmi3GetIntervalFraction", nValueReferences);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                               fmi3Float64 shifts[]) {
    GET_INSTANCE("fmi3GetShiftDecimal");
    (void)valueReferences;
    (void)shifts;
    return no_variables(inst, "fmi3GetShiftDecimal", nValueReferences);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    GET_INSTANCE("fmi3GetShiftFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    return no_variables(inst, "fmi3GetShiftFraction", nValueReferences);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                  const fmi3Float64 intervals[]) {
    GET_INSTANCE("fmi3SetIntervalDecimal");
    (void)valueReferences;
    (void)intervals;
    return no_variables(inst, "fmi3SetIntervalDecimal", nValueReferences);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    GET_INSTANCE("fmi3SetIntervalFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    return no_variables(inst, "fmi3SetIntervalFraction", nValueReferences);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                               const fmi3Float64 shifts[]) {
    GET_INSTANCE("fmi3SetShiftDecimal");
    (void)valueReferences;
    (void)shifts;
    return no_variables(inst, "fmi3SetShiftDecimal", nValueReferences);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    GET_INSTANCE("fmi3SetShiftFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    return no_variables(inst, "fmi3SetShiftFraction", nValueReferences);
}

/* ------------------------------------------------------------ unsupported optional features */
#define UNSUPPORTED0(Name, why)                                                                                        \
    fmi3Status fmi3##Name(fmi3Instance instance) {                                                                     \
        GET_INSTANCE("fmi3" #Name);                                                                                    \
        return refuse(inst, "fmi3" #Name, why);                                                                        \
    }

UNSUPPORTED0(EnterConfigurationMode, "not supported (no structural parameters)")
UNSUPPORTED0(ExitConfigurationMode, "not supported (no structural parameters)")
UNSUPPORTED0(EvaluateDiscreteStates, "not supported (no clocks)")
UNSUPPORTED0(EnterContinuousTimeMode, "Model Exchange only")
UNSUPPORTED0(EnterStepMode, "not supported (no event mode: the FMU is in step mode after initialization)")

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference, size_t *nDependencies) {
    GET_INSTANCE("fmi3GetNumberOfVariableDependencies");
    (void)valueReference;
    (void)nDependencies;
    return refuse(inst, "fmi3GetNumberOfVariableDependencies", "not supported (see ModelStructure)");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[], size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    GET_INSTANCE("fmi3GetVariableDependencies");
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return refuse(inst, "fmi3GetVariableDependencies", "not supported (see ModelStructure)");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    GET_INSTANCE("fmi3GetDirectionalDerivative");
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return refuse(inst, "fmi3GetDirectionalDerivative", "not supported (providesDirectionalDerivatives = false)");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    GET_INSTANCE("fmi3GetAdjointDerivative");
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return refuse(inst, "fmi3GetAdjointDerivative", "not supported (providesAdjointDerivatives = false)");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime) {
    GET_INSTANCE("fmi3ActivateModelPartition");
    (void)clockReference;
    (void)activationTime;
    return refuse(inst, "fmi3ActivateModelPartition", "not supported (no Scheduled Execution)");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate, fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged, fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    GET_INSTANCE("fmi3UpdateDiscreteStates");
    (void)discreteStatesNeedUpdate;
    (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined;
    (void)nextEventTime;
    return refuse(inst, "fmi3UpdateDiscreteStates", "not supported (no event mode)");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    GET_INSTANCE("fmi3CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return refuse(inst, "fmi3CompletedIntegratorStep", "Model Exchange only");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    GET_INSTANCE("fmi3SetTime");
    (void)time;
    return refuse(inst, "fmi3SetTime", "Model Exchange only");
}

#define ME_ARRAY(Name, Type, CONST)                                                                                    \
    fmi3Status fmi3##Name(fmi3Instance instance, CONST Type values[], size_t n) {                                      \
        GET_INSTANCE("fmi3" #Name);                                                                                    \
        (void)values;                                                                                                  \
        (void)n;                                                                                                       \
        return refuse(inst, "fmi3" #Name, "Model Exchange only (the controller has no continuous states)");            \
    }
#define NOCONST
ME_ARRAY(SetContinuousStates, fmi3Float64, const)
ME_ARRAY(GetContinuousStateDerivatives, fmi3Float64, NOCONST)
ME_ARRAY(GetEventIndicators, fmi3Float64, NOCONST)
ME_ARRAY(GetContinuousStates, fmi3Float64, NOCONST)
ME_ARRAY(GetNominalsOfContinuousStates, fmi3Float64, NOCONST)

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    GET_INSTANCE("fmi3GetNumberOfEventIndicators");
    if (nEventIndicators == NULL) return refuse(inst, "fmi3GetNumberOfEventIndicators", "NULL argument");
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    GET_INSTANCE("fmi3GetNumberOfContinuousStates");
    if (nContinuousStates == NULL) return refuse(inst, "fmi3GetNumberOfContinuousStates", "NULL argument");
    *nContinuousStates = 0;
    return fmi3OK;
}

/* ------------------------------------------------------------ FMU state */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    GET_INSTANCE("fmi3GetFMUState");
    if (ctrl_check(inst, CMS_ANY & ~CMS_ERROR, "fmi3GetFMUState") != CST_OK) return fmi3Error;
    if (FMUState == NULL) return refuse(inst, "fmi3GetFMUState", "FMUState is NULL");
    if (*FMUState == NULL) {
        *FMUState = malloc(sizeof(CtrlData));
        if (*FMUState == NULL) return refuse(inst, "fmi3GetFMUState", "out of memory");
    } else if (ctrl_check_state(inst, *FMUState, sizeof(CtrlData), "fmi3GetFMUState") != CST_OK) {
        return fmi3Error;
    }
    memcpy(*FMUState, &inst->d, sizeof(CtrlData));
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    GET_INSTANCE("fmi3SetFMUState");
    return (fmi3Status)ctrl_restore(inst, FMUState, "fmi3SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    GET_INSTANCE("fmi3FreeFMUState");
    if (FMUState == NULL) return refuse(inst, "fmi3FreeFMUState", "FMUState is NULL");
    if (ctrl_is_state_block(FMUState)) { /* the importer passed the state, not its address: free it, never crash */
        free(FMUState);
        ctrl_logf(inst, CST_WARNING, "fmi3FreeFMUState: got the FMU state itself instead of a pointer to it (importer bug); "
                  "the state was freed, the importer's variable still holds the freed address");
        return fmi3OK; /* as the plant FMUs: the call did what it was meant to */
    }
    free(*FMUState);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    GET_INSTANCE("fmi3SerializedFMUStateSize");
    if (size == NULL) return refuse(inst, "fmi3SerializedFMUStateSize", "size is NULL");
    if (ctrl_check_state(inst, FMUState, sizeof(CtrlData), "fmi3SerializedFMUStateSize") != CST_OK) return fmi3Error;
    *size = sizeof(CtrlData);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    GET_INSTANCE("fmi3SerializeFMUState");
    if (ctrl_check_state(inst, FMUState, sizeof(CtrlData), "fmi3SerializeFMUState") != CST_OK) return fmi3Error;
    if (serializedState == NULL || size != sizeof(CtrlData)) return refuse(inst, "fmi3SerializeFMUState", "bad buffer");
    memcpy(serializedState, FMUState, sizeof(CtrlData));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size, fmi3FMUState *FMUState) {
    GET_INSTANCE("fmi3DeserializeFMUState");
    if (FMUState == NULL) return refuse(inst, "fmi3DeserializeFMUState", "FMUState is NULL");
    if (ctrl_check_state(inst, serializedState, size, "fmi3DeserializeFMUState") != CST_OK) return fmi3Error;
    if (*FMUState == NULL) {
        *FMUState = malloc(sizeof(CtrlData));
        if (*FMUState == NULL) return refuse(inst, "fmi3DeserializeFMUState", "out of memory");
    }
    memcpy(*FMUState, serializedState, sizeof(CtrlData));
    return fmi3OK;
}

/* ------------------------------------------------------------ Co-Simulation */
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    GET_INSTANCE("fmi3GetOutputDerivatives");
    (void)valueReferences;
    (void)nValueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    return refuse(inst, "fmi3GetOutputDerivatives", "not supported (maxOutputDerivativeOrder = 0)");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    GET_INSTANCE("fmi3DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL || lastSuccessfulTime == NULL)
        return refuse(inst, "fmi3DoStep", "NULL output argument");
    fmi3Status s = (fmi3Status)ctrl_do_step(inst, currentCommunicationPoint, communicationStepSize, "fmi3DoStep");
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = inst->d.time;
    return s;
}
