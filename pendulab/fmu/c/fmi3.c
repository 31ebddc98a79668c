/* FMI 3.0 layer (Co-Simulation and Model Exchange) over the model core. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmu_core.h"

/* fmi3Int32 values are passed to the core as int */
typedef char fmi3_int32_is_int[sizeof(int) == sizeof(fmi3Int32) ? 1 : -1];

typedef struct {
    Instance core;
    fmi3LogMessageCallback logMessage;
} Fmi3Instance;

static void fmi3_log(Instance *inst, CoreStatus status, const char *category, const char *message) {
    Fmi3Instance *c = (Fmi3Instance *)inst;
    if (c->logMessage != NULL) c->logMessage(inst->env, (fmi3Status)status, category, message);
}

#define GET_INSTANCE(fname)                                                                                           \
    Fmi3Instance *c3 = (Fmi3Instance *)instance;                                                                      \
    if (c3 == NULL) return fmi3Error;                                                                                 \
    Instance *inst = &c3->core;                                                                                       \
    core_debugf(inst, "%s", fname)

#define CHECK_STATE(allowed, fname)                                                                                   \
    if (core_check(inst, (allowed), (fname)) != ST_OK) return fmi3Error

#define ME_ONLY(fname)                                                                                                \
    if (inst->is_cosim) {                                                                                             \
        core_logf(inst, ST_ERROR, "%s: only available for Model Exchange", fname);                                    \
        return fmi3Error;                                                                                             \
    }

#define CS_ONLY(fname)                                                                                                \
    if (!inst->is_cosim) {                                                                                            \
        core_logf(inst, ST_ERROR, "%s: only available for Co-Simulation", fname);                                     \
        return fmi3Error;                                                                                             \
    }

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories, const fmi3String categories[]) {
    GET_INSTANCE("fmi3SetDebugLogging");
    if (nCategories > 0 && categories == NULL) {
        core_logf(inst, ST_ERROR, "fmi3SetDebugLogging: categories is NULL with nCategories = %zu", nCategories);
        return fmi3Error;
    }
    for (size_t i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (cat == NULL || (strcmp(cat, "logStatusError") && strcmp(cat, "logStatusWarning") && strcmp(cat, "logCalls"))) {
            core_logf(inst, ST_ERROR, "fmi3SetDebugLogging: unknown log category %s", cat ? cat : "(NULL)");
            return fmi3Error;
        }
    }
    inst->logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

static fmi3Instance instantiate(fmi3String instanceName, fmi3String token, fmi3Boolean loggingOn,
                                fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage, int is_cosim) {
    Fmi3Instance tmp;
    memset(&tmp, 0, sizeof(tmp));
    tmp.logMessage = logMessage;
    tmp.core.log = fmi3_log;
    tmp.core.env = env;
    snprintf(tmp.core.name, sizeof(tmp.core.name), "%s", instanceName ? instanceName : "");
    if (instanceName == NULL || instanceName[0] == '\0') {
        core_logf(&tmp.core, ST_ERROR, "fmi3Instantiate: missing instance name");
        return NULL;
    }
    if (token == NULL || strcmp(token, MODEL_TOKEN) != 0) {
        core_logf(&tmp.core, ST_ERROR, "fmi3Instantiate: instantiation token %s does not match %s", token ? token : "(NULL)",
                  MODEL_TOKEN);
        return NULL;
    }
    Fmi3Instance *c = (Fmi3Instance *)calloc(1, sizeof(Fmi3Instance));
    if (c == NULL) {
        core_logf(&tmp.core, ST_ERROR, "fmi3Instantiate: out of memory");
        return NULL;
    }
    memcpy(c, &tmp, sizeof(tmp));
    c->core.is_cosim = is_cosim;
    c->core.logging_on = loggingOn ? 1 : 0;
    core_defaults(&c->core);
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                          fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)resourcePath;
    (void)visible;
    return instantiate(instanceName, instantiationToken, loggingOn, instanceEnvironment, logMessage, 0);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                         fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath;
    (void)visible;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    if (eventModeUsed && MODEL_NF == 0) {
        /* event mode only with flip events (hasEventMode = true): refuse rather than ignore the request */
        if (logMessage != NULL)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateCoSimulation: eventModeUsed is not supported (hasEventMode = false: export "
                       "with flip events for a CS event mode)");
        return NULL;
    }
    Fmi3Instance *c = (Fmi3Instance *)instantiate(instanceName, instantiationToken, loggingOn, instanceEnvironment,
                                                  logMessage, 1);
    if (c != NULL) {
        c->core.early_return = earlyReturnAllowed ? 1 : 0; /* a spring limit or (event mode) a flip ends a step early */
        c->core.event_mode_used = eventModeUsed ? 1 : 0;
    }
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
    CHECK_STATE(MS_INSTANTIATED, "fmi3EnterInitializationMode");
    if (stopTimeDefined && !(stopTime >= startTime)) {
        core_logf(inst, ST_ERROR, "fmi3EnterInitializationMode: stop time %g before start time %g", stopTime, startTime);
        return fmi3Error;
    }
    CoreStatus s = core_set_experiment(inst, toleranceDefined != 0, tolerance, startTime);
    if (s != ST_OK) return (fmi3Status)s;
    inst->d.machine = MS_INIT;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3ExitInitializationMode");
    CHECK_STATE(MS_INIT, "fmi3ExitInitializationMode");
    CoreStatus s = core_exit_initialization(inst);
    if (s != ST_OK) {
        inst->d.machine = MS_ERROR;
        return (fmi3Status)s;
    }
    inst->d.machine = inst->is_cosim && !inst->event_mode_used ? MS_STEP : MS_EVENT; /* CS event mode: Event Mode */
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3EnterEventMode");
    if (inst->is_cosim && !inst->event_mode_used) {
        core_logf(inst, ST_ERROR, "fmi3EnterEventMode: Co-Simulation without eventModeUsed has no event mode");
        return fmi3Error;
    }
    CHECK_STATE(inst->is_cosim ? MS_STEP : (MS_EVENT | MS_CONT), "fmi3EnterEventMode");
    inst->d.machine = MS_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    GET_INSTANCE("fmi3Terminate");
    CHECK_STATE(MS_STEP | MS_EVENT | MS_CONT, "fmi3Terminate");
    inst->d.machine = MS_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    GET_INSTANCE("fmi3Reset");
    core_defaults(inst);
    return fmi3OK;
}

/* ------------------------------------------------------------ variables */
static int counts_match(Instance *inst, const char *fname, size_t nvr, size_t nvalues) {
    if (nvr == nvalues) return 1;
    core_logf(inst, ST_ERROR, "%s: %zu value references but %zu values (all variables are scalars)", fname, nvr, nvalues);
    return 0;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    GET_INSTANCE("fmi3GetFloat64");
    if (!counts_match(inst, "fmi3GetFloat64", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)core_get_real(inst, "fmi3GetFloat64", valueReferences, nValueReferences, values);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    GET_INSTANCE("fmi3SetFloat64");
    if (!counts_match(inst, "fmi3SetFloat64", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)core_set_real(inst, "fmi3SetFloat64", valueReferences, nValueReferences, values);
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int32 values[], size_t nValues) {
    GET_INSTANCE("fmi3GetInt32");
    if (!counts_match(inst, "fmi3GetInt32", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)core_get_int(inst, "fmi3GetInt32", valueReferences, nValueReferences, (int *)values);
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int32 values[], size_t nValues) {
    GET_INSTANCE("fmi3SetInt32");
    if (!counts_match(inst, "fmi3SetInt32", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)core_set_int(inst, "fmi3SetInt32", valueReferences, nValueReferences, (const int *)values);
}

/* Types the model has no variables of: any non-empty access is an unknown value reference. */
static fmi3Status no_such_variable(Instance *inst, const char *fname, size_t nvr) {
    if (nvr == 0) return fmi3OK;
    core_logf(inst, ST_ERROR, "%s: this model has no variables of that type", fname);
    return fmi3Error;
}

#define NO_VARIABLES(NAME, TYPE, CONST)                                                                               \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                             TYPE values[], size_t nValues) {                                                         \
        GET_INSTANCE("fmi3Get" #NAME);                                                                                \
        (void)valueReferences;                                                                                        \
        (void)values;                                                                                                 \
        (void)nValues;                                                                                                \
        return no_such_variable(inst, "fmi3Get" #NAME, nValueReferences);                                             \
    }                                                                                                                 \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                             CONST TYPE values[], size_t nValues) {                                                   \
        GET_INSTANCE("fmi3Set" #NAME);                                                                                \
        (void)valueReferences;                                                                                        \
        (void)values;                                                                                                 \
        (void)nValues;                                                                                                \
        return no_such_variable(inst, "fmi3Set" #NAME, nValueReferences);                                             \
    }

NO_VARIABLES(Float32, fmi3Float32, const)
NO_VARIABLES(Int8, fmi3Int8, const)
NO_VARIABLES(UInt8, fmi3UInt8, const)
NO_VARIABLES(Int16, fmi3Int16, const)
NO_VARIABLES(UInt16, fmi3UInt16, const)
NO_VARIABLES(UInt32, fmi3UInt32, const)
NO_VARIABLES(Int64, fmi3Int64, const)
NO_VARIABLES(UInt64, fmi3UInt64, const)
NO_VARIABLES(Boolean, fmi3Boolean, const)
NO_VARIABLES(String, fmi3String, const)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    GET_INSTANCE("fmi3GetBinary");
    (void)valueReferences;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_such_variable(inst, "fmi3GetBinary", nValueReferences);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    GET_INSTANCE("fmi3SetBinary");
    (void)valueReferences;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_such_variable(inst, "fmi3SetBinary", nValueReferences);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[]) {
    GET_INSTANCE("fmi3GetClock");
    (void)valueReferences;
    (void)values;
    return no_such_variable(inst, "fmi3GetClock", nValueReferences);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[]) {
    GET_INSTANCE("fmi3SetClock");
    (void)valueReferences;
    (void)values;
    return no_such_variable(inst, "fmi3SetClock", nValueReferences);
}

/* ------------------------------------------------------------ unsupported optional features */
static fmi3Status unsupported(Instance *inst, const char *fname) {
    core_logf(inst, ST_ERROR, "%s: not supported by this FMU", fname);
    return fmi3Error;
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference, size_t *nDependencies) {
    GET_INSTANCE("fmi3GetNumberOfVariableDependencies");
    (void)valueReference;
    (void)nDependencies;
    return unsupported(inst, "fmi3GetNumberOfVariableDependencies (see ModelStructure)");
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
    return unsupported(inst, "fmi3GetVariableDependencies (see ModelStructure)");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    /* sensitivity = J' seed for J = d(unknowns)/d(knowns): CasADi's reverse mode (MODEL_ADJOINT, generated from the
     * same graph as the directional derivatives) applied to the seed scattered onto all derivatives and outputs. */
    enum { NR = MODEL_NX + MODEL_NY, NC = MODEL_NX + MODEL_NU };
    GET_INSTANCE("fmi3GetAdjointDerivative");
    CHECK_STATE(MS_INIT | MS_STEP | MS_EVENT | MS_CONT | MS_TERMINATED, "fmi3GetAdjointDerivative");
    if (nSeed != nUnknowns || nSensitivity != nKnowns) {
        core_logf(inst, ST_ERROR, "fmi3GetAdjointDerivative: nSeed (%zu) must equal nUnknowns (%zu) and nSensitivity (%zu) "
                  "nKnowns (%zu)", nSeed, nUnknowns, nSensitivity, nKnowns);
        return fmi3Error;
    }
    if ((nUnknowns > 0 && (unknowns == NULL || seed == NULL)) || (nKnowns > 0 && (knowns == NULL || sensitivity == NULL))) {
        core_logf(inst, ST_ERROR, "fmi3GetAdjointDerivative: NULL array argument");
        return fmi3Error;
    }
    if (nUnknowns > NR || nKnowns > NC) {
        core_logf(inst, ST_ERROR, "fmi3GetAdjointDerivative: too many unknowns (%zu) or knowns (%zu)", nUnknowns, nKnowns);
        return fmi3Error;
    }
    double v[NR], w[NC];
    int cols[NC];
    for (int r = 0; r < NR; r++) v[r] = 0.0;
    for (size_t i = 0; i < nUnknowns; i++) {
        int k;
        VarKind kind = core_classify(unknowns[i], &k);
        if (kind != KIND_DERIV && kind != KIND_OUTPUT) {
            core_logf(inst, ST_ERROR, "fmi3GetAdjointDerivative: unknown %u is not a derivative or output", unknowns[i]);
            return fmi3Error;
        }
        if (!isfinite(seed[i])) {
            core_logf(inst, ST_ERROR, "fmi3GetAdjointDerivative: seed %zu is not finite", i);
            return fmi3Error;
        }
        v[kind == KIND_DERIV ? k : MODEL_NX + k] += seed[i]; /* a repeated unknown adds its seeds */
    }
    for (size_t j = 0; j < nKnowns; j++) {
        int k;
        VarKind kind = core_classify(knowns[j], &k);
        if (kind != KIND_STATE && kind != KIND_INPUT) {
            core_logf(inst, ST_ERROR, "fmi3GetAdjointDerivative: known %u is not a state or input", knowns[j]);
            return fmi3Error;
        }
        cols[j] = kind == KIND_STATE ? k : MODEL_NX + k;
    }
    inst->arg[0] = inst->d.x;
    inst->arg[1] = inst->d.u;
    inst->arg[2] = inst->d.p;
    inst->arg[3] = v;
    inst->res[0] = w;
    int bad = MODEL_ADJOINT(inst->arg, inst->res, inst->iw, inst->w, 0) != 0;
    for (int c = 0; c < NC && !bad; c++) bad = !isfinite(w[c]);
    if (bad) {
        core_logf(inst, ST_ERROR, "fmi3GetAdjointDerivative: adjoint evaluation failed");
        return fmi3Error;
    }
    for (size_t j = 0; j < nKnowns; j++) sensitivity[j] = w[cols[j]];
    return fmi3OK;
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3EnterConfigurationMode");
    return unsupported(inst, "fmi3EnterConfigurationMode (no structural parameters)");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3ExitConfigurationMode");
    return unsupported(inst, "fmi3ExitConfigurationMode (no structural parameters)");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    GET_INSTANCE("fmi3GetIntervalDecimal");
    (void)valueReferences;
    (void)intervals;
    (void)qualifiers;
    return no_such_variable(inst, "fmi3GetIntervalDecimal", nValueReferences);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    GET_INSTANCE("fmi3GetIntervalFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return no_such_variable(inst, "fmi3GetIntervalFraction", nValueReferences);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                               fmi3Float64 shifts[]) {
    GET_INSTANCE("fmi3GetShiftDecimal");
    (void)valueReferences;
    (void)shifts;
    return no_such_variable(inst, "fmi3GetShiftDecimal", nValueReferences);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    GET_INSTANCE("fmi3GetShiftFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    return no_such_variable(inst, "fmi3GetShiftFraction", nValueReferences);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                  const fmi3Float64 intervals[]) {
    GET_INSTANCE("fmi3SetIntervalDecimal");
    (void)valueReferences;
    (void)intervals;
    return no_such_variable(inst, "fmi3SetIntervalDecimal", nValueReferences);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    GET_INSTANCE("fmi3SetIntervalFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    return no_such_variable(inst, "fmi3SetIntervalFraction", nValueReferences);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                               const fmi3Float64 shifts[]) {
    GET_INSTANCE("fmi3SetShiftDecimal");
    (void)valueReferences;
    (void)shifts;
    return no_such_variable(inst, "fmi3SetShiftDecimal", nValueReferences);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    GET_INSTANCE("fmi3SetShiftFraction");
    (void)valueReferences;
    (void)counters;
    (void)resolutions;
    return no_such_variable(inst, "fmi3SetShiftFraction", nValueReferences);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    GET_INSTANCE("fmi3EvaluateDiscreteStates");
    return unsupported(inst, "fmi3EvaluateDiscreteStates (no clocks)");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime) {
    GET_INSTANCE("fmi3ActivateModelPartition");
    (void)clockReference;
    (void)activationTime;
    return unsupported(inst, "fmi3ActivateModelPartition (no Scheduled Execution)");
}

/* ------------------------------------------------------------ FMU state */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    GET_INSTANCE("fmi3GetFMUState");
    CHECK_STATE(MS_ANY & ~MS_ERROR, "fmi3GetFMUState");
    if (FMUState == NULL) {
        core_logf(inst, ST_ERROR, "fmi3GetFMUState: FMUState is NULL");
        return fmi3Error;
    }
    if (*FMUState == NULL) {
        *FMUState = malloc(sizeof(CoreData));
        if (*FMUState == NULL) {
            core_logf(inst, ST_ERROR, "fmi3GetFMUState: out of memory");
            return fmi3Error;
        }
    } else if (core_check_state_blob(inst, *FMUState, sizeof(CoreData), "fmi3GetFMUState") != ST_OK) {
        return fmi3Error;
    }
    memcpy(*FMUState, &inst->d, sizeof(CoreData));
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    GET_INSTANCE("fmi3SetFMUState");
    CHECK_STATE(MS_ANY, "fmi3SetFMUState"); /* also in Error: restart from a stored state */
    return (fmi3Status)core_restore(inst, (const CoreData *)FMUState, "fmi3SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    GET_INSTANCE("fmi3FreeFMUState");
    if (FMUState == NULL) {
        core_logf(inst, ST_ERROR, "fmi3FreeFMUState: FMUState is NULL");
        return fmi3Error;
    }
    if (core_is_state_block(FMUState)) { /* the importer passed the state, not its address: free it, never crash */
        free(FMUState);
        core_logf(inst, ST_WARNING, "fmi3FreeFMUState: got the FMU state itself instead of a pointer to it (importer "
                  "bug); the state was freed, the importer's variable still holds the freed address");
        return fmi3OK; /* the call did what it was meant to; importers abort on Warning (fmusim 0.0.39) */
    }
    free(*FMUState);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    GET_INSTANCE("fmi3SerializedFMUStateSize");
    if (size == NULL) {
        core_logf(inst, ST_ERROR, "fmi3SerializedFMUStateSize: size is NULL");
        return fmi3Error;
    }
    if (core_check_state_blob(inst, FMUState, sizeof(CoreData), "fmi3SerializedFMUStateSize") != ST_OK) return fmi3Error;
    *size = sizeof(CoreData);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    GET_INSTANCE("fmi3SerializeFMUState");
    if (core_check_state_blob(inst, FMUState, sizeof(CoreData), "fmi3SerializeFMUState") != ST_OK) return fmi3Error;
    if (serializedState == NULL || size != sizeof(CoreData)) {
        core_logf(inst, ST_ERROR, "fmi3SerializeFMUState: buffer is NULL or has %zu bytes, expected %zu", size,
                  sizeof(CoreData));
        return fmi3Error;
    }
    memcpy(serializedState, FMUState, sizeof(CoreData));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size, fmi3FMUState *FMUState) {
    GET_INSTANCE("fmi3DeserializeFMUState");
    if (FMUState == NULL) {
        core_logf(inst, ST_ERROR, "fmi3DeserializeFMUState: FMUState is NULL");
        return fmi3Error;
    }
    if (core_check_state_blob(inst, serializedState, size, "fmi3DeserializeFMUState") != ST_OK) return fmi3Error;
    if (*FMUState == NULL) {
        *FMUState = malloc(sizeof(CoreData));
        if (*FMUState == NULL) {
            core_logf(inst, ST_ERROR, "fmi3DeserializeFMUState: out of memory");
            return fmi3Error;
        }
    }
    memcpy(*FMUState, serializedState, sizeof(CoreData));
    return fmi3OK;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    GET_INSTANCE("fmi3GetDirectionalDerivative");
    CHECK_STATE(MS_INIT | MS_STEP | MS_EVENT | MS_CONT | MS_TERMINATED, "fmi3GetDirectionalDerivative");
    if (nSeed != nKnowns || nSensitivity != nUnknowns) {
        core_logf(inst, ST_ERROR, "fmi3GetDirectionalDerivative: nSeed (%zu) must equal nKnowns (%zu) and nSensitivity (%zu) "
                  "nUnknowns (%zu)", nSeed, nKnowns, nSensitivity, nUnknowns);
        return fmi3Error;
    }
    return (fmi3Status)core_directional(inst, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity);
}

/* ------------------------------------------------------------ Model Exchange */
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate, fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged, fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    GET_INSTANCE("fmi3UpdateDiscreteStates");
    if (inst->is_cosim && !inst->event_mode_used) {
        core_logf(inst, ST_ERROR, "fmi3UpdateDiscreteStates: Co-Simulation without eventModeUsed has no event mode");
        return fmi3Error;
    }
    CHECK_STATE(MS_EVENT, "fmi3UpdateDiscreteStates");
    inst->event_pending = 0; /* a flip changes no discrete state: handled */
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False;
    if (terminateSimulation)
        *terminateSimulation = core_spring_event(inst, "fmi3UpdateDiscreteStates") ? fmi3True : fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = fmi3False;
    if (nextEventTimeDefined) *nextEventTimeDefined = fmi3False;
    if (nextEventTime) *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3EnterContinuousTimeMode");
    ME_ONLY("fmi3EnterContinuousTimeMode");
    CHECK_STATE(MS_EVENT, "fmi3EnterContinuousTimeMode");
    inst->d.machine = MS_CONT;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    GET_INSTANCE("fmi3CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    ME_ONLY("fmi3CompletedIntegratorStep");
    CHECK_STATE(MS_CONT, "fmi3CompletedIntegratorStep");
    if (enterEventMode == NULL || terminateSimulation == NULL) {
        core_logf(inst, ST_ERROR, "fmi3CompletedIntegratorStep: NULL output argument");
        return fmi3Error;
    }
    *enterEventMode = fmi3False;
    *terminateSimulation = core_spring_event(inst, "fmi3CompletedIntegratorStep") ? fmi3True : fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    GET_INSTANCE("fmi3SetTime");
    ME_ONLY("fmi3SetTime");
    CHECK_STATE(MS_EVENT | MS_CONT, "fmi3SetTime");
    return (fmi3Status)core_set_time(inst, time);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t nContinuousStates) {
    GET_INSTANCE("fmi3SetContinuousStates");
    ME_ONLY("fmi3SetContinuousStates");
    CHECK_STATE(MS_CONT, "fmi3SetContinuousStates");
    return (fmi3Status)core_set_states(inst, continuousStates, nContinuousStates);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t nContinuousStates) {
    GET_INSTANCE("fmi3GetContinuousStateDerivatives");
    ME_ONLY("fmi3GetContinuousStateDerivatives");
    CHECK_STATE(MS_INIT | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR, "fmi3GetContinuousStateDerivatives");
    if (derivatives == NULL || nContinuousStates != MODEL_NX) {
        core_logf(inst, ST_ERROR, "fmi3GetContinuousStateDerivatives: expected a non-NULL array of %d, got n = %zu", MODEL_NX,
                  nContinuousStates);
        return fmi3Error;
    }
    return (fmi3Status)core_derivatives(inst, derivatives);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    GET_INSTANCE("fmi3GetEventIndicators");
    ME_ONLY("fmi3GetEventIndicators");
    CHECK_STATE(MS_INIT | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR, "fmi3GetEventIndicators");
    return (fmi3Status)core_event_indicators(inst, eventIndicators, nEventIndicators, "fmi3GetEventIndicators");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    GET_INSTANCE("fmi3GetContinuousStates");
    ME_ONLY("fmi3GetContinuousStates");
    CHECK_STATE(MS_INIT | MS_EVENT | MS_CONT | MS_TERMINATED | MS_ERROR, "fmi3GetContinuousStates");
    if (continuousStates == NULL || nContinuousStates != MODEL_NX) {
        core_logf(inst, ST_ERROR, "fmi3GetContinuousStates: expected a non-NULL array of %d, got n = %zu", MODEL_NX,
                  nContinuousStates);
        return fmi3Error;
    }
    memcpy(continuousStates, inst->d.x, sizeof(inst->d.x));
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates) {
    GET_INSTANCE("fmi3GetNominalsOfContinuousStates");
    ME_ONLY("fmi3GetNominalsOfContinuousStates");
    if (nominals == NULL || nContinuousStates != MODEL_NX) {
        core_logf(inst, ST_ERROR, "fmi3GetNominalsOfContinuousStates: expected a non-NULL array of %d, got n = %zu", MODEL_NX,
                  nContinuousStates);
        return fmi3Error;
    }
    for (int i = 0; i < MODEL_NX; i++) nominals[i] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    GET_INSTANCE("fmi3GetNumberOfEventIndicators");
    if (nEventIndicators == NULL) {
        core_logf(inst, ST_ERROR, "fmi3GetNumberOfEventIndicators: NULL argument");
        return fmi3Error;
    }
    *nEventIndicators = MODEL_NZ;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    GET_INSTANCE("fmi3GetNumberOfContinuousStates");
    if (nContinuousStates == NULL) {
        core_logf(inst, ST_ERROR, "fmi3GetNumberOfContinuousStates: NULL argument");
        return fmi3Error;
    }
    *nContinuousStates = MODEL_NX;
    return fmi3OK;
}

/* ------------------------------------------------------------ Co-Simulation */
fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    GET_INSTANCE("fmi3EnterStepMode");
    CS_ONLY("fmi3EnterStepMode");
    if (!inst->event_mode_used)
        return unsupported(inst, "fmi3EnterStepMode (no event mode: the FMU is in step mode after initialization)");
    CHECK_STATE(MS_EVENT, "fmi3EnterStepMode");
    inst->d.machine = MS_STEP;
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    GET_INSTANCE("fmi3GetOutputDerivatives");
    (void)valueReferences;
    (void)nValueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    return unsupported(inst, "fmi3GetOutputDerivatives (maxOutputDerivativeOrder = 0)");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    GET_INSTANCE("fmi3DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    CS_ONLY("fmi3DoStep");
    CHECK_STATE(MS_STEP, "fmi3DoStep");
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL || lastSuccessfulTime == NULL) {
        core_logf(inst, ST_ERROR, "fmi3DoStep: NULL output argument");
        return fmi3Error;
    }
    CoreStatus s = core_do_step(inst, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = inst->event_pending ? fmi3True : fmi3False; /* a flip (event mode) */
    *terminateSimulation = inst->terminate_requested ? fmi3True : fmi3False;
    *earlyReturn = s == ST_OK && inst->event_pending && inst->d.time < currentCommunicationPoint + communicationStepSize;
    *lastSuccessfulTime = inst->d.time;
    if (s == ST_DISCARD && inst->terminate_requested && inst->early_return) {
        /* a spring reached its limit: the step ended early at lastSuccessfulTime, and the FMU asks to stop */
        *earlyReturn = fmi3True;
        return fmi3OK;
    }
    return (fmi3Status)s; /* without early return: Discard, terminateSimulation, lastSuccessfulTime */
}
