/* Two source FMUs (rigid and elastic) compiled with different function prefixes and linked statically
 * into this one program: the standard FMI headers rename fmi2* / fmi3* with FMI2_FUNCTION_PREFIX /
 * FMI3_FUNCTION_PREFIX and the FMU's model.h renames everything else, so no symbol clashes.
 * Build: -DFMI_VERSION=2|3, objects of the rigid FMU with prefix rigid_, of the elastic FMU with elastic_.
 * usage: static_link_two <rigid token> <elastic token> <n_steps>; prints "rigid=<theta1> elastic=<theta1>". */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if FMI_VERSION == 2
#include "fmi2Functions.h"
#define DECLARE(prefix)                                                                                               \
    fmi2InstantiateTYPE prefix##fmi2Instantiate;                                                                      \
    fmi2FreeInstanceTYPE prefix##fmi2FreeInstance;                                                                    \
    fmi2SetupExperimentTYPE prefix##fmi2SetupExperiment;                                                              \
    fmi2EnterInitializationModeTYPE prefix##fmi2EnterInitializationMode;                                              \
    fmi2ExitInitializationModeTYPE prefix##fmi2ExitInitializationMode;                                                \
    fmi2DoStepTYPE prefix##fmi2DoStep;                                                                                \
    fmi2GetRealTYPE prefix##fmi2GetReal;                                                                              \
    fmi2SetRealTYPE prefix##fmi2SetReal;
DECLARE(rigid_)
DECLARE(elastic_)

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)category;
    if (status >= fmi2Error) fprintf(stderr, "%s: %s\n", name, message);
}

#define RUN(prefix, token, out)                                                                                       \
    do {                                                                                                              \
        fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};                                                \
        fmi2Component c = prefix##fmi2Instantiate(#prefix, fmi2CoSimulation, token, "", &cb, fmi2False, fmi2False);  \
        const fmi2ValueReference vr = 100;                                                                            \
        fmi2Real x0 = 1.0;                                                                                            \
        if (c == NULL || prefix##fmi2SetReal(c, &vr, 1, &x0) != fmi2OK ||                                             \
            prefix##fmi2SetupExperiment(c, fmi2True, 1e-10, 0.0, fmi2False, 0.0) != fmi2OK ||                        \
            prefix##fmi2EnterInitializationMode(c) != fmi2OK || prefix##fmi2ExitInitializationMode(c) != fmi2OK)     \
            return 1;                                                                                                 \
        for (int k = 0; k < n; k++)                                                                                   \
            if (prefix##fmi2DoStep(c, k * 0.01, 0.01, fmi2True) != fmi2OK) return 1;                                  \
        if (prefix##fmi2GetReal(c, &vr, 1, &out) != fmi2OK) return 1;                                                 \
        prefix##fmi2FreeInstance(c);                                                                                  \
    } while (0)
#else
#include "fmi3Functions.h"
#define DECLARE(prefix)                                                                                               \
    fmi3InstantiateCoSimulationTYPE prefix##fmi3InstantiateCoSimulation;                                              \
    fmi3FreeInstanceTYPE prefix##fmi3FreeInstance;                                                                    \
    fmi3EnterInitializationModeTYPE prefix##fmi3EnterInitializationMode;                                              \
    fmi3ExitInitializationModeTYPE prefix##fmi3ExitInitializationMode;                                                \
    fmi3DoStepTYPE prefix##fmi3DoStep;                                                                                \
    fmi3GetFloat64TYPE prefix##fmi3GetFloat64;                                                                        \
    fmi3SetFloat64TYPE prefix##fmi3SetFloat64;
DECLARE(rigid_)
DECLARE(elastic_)

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    (void)category;
    if (status >= fmi3Error) fprintf(stderr, "%s\n", message);
}

#define RUN(prefix, token, out)                                                                                       \
    do {                                                                                                              \
        fmi3Instance c = prefix##fmi3InstantiateCoSimulation(#prefix, token, "", fmi3False, fmi3False, fmi3False,    \
                                                             fmi3False, NULL, 0, NULL, logger, NULL);                 \
        const fmi3ValueReference vr = 100;                                                                            \
        fmi3Float64 x0 = 1.0, last;                                                                                   \
        fmi3Boolean ev, term, early;                                                                                  \
        if (c == NULL || prefix##fmi3SetFloat64(c, &vr, 1, &x0, 1) != fmi3OK ||                                      \
            prefix##fmi3EnterInitializationMode(c, fmi3True, 1e-10, 0.0, fmi3False, 0.0) != fmi3OK ||                \
            prefix##fmi3ExitInitializationMode(c) != fmi3OK)                                                          \
            return 1;                                                                                                 \
        for (int k = 0; k < n; k++)                                                                                   \
            if (prefix##fmi3DoStep(c, k * 0.01, 0.01, fmi3True, &ev, &term, &early, &last) != fmi3OK) return 1;       \
        if (prefix##fmi3GetFloat64(c, &vr, 1, &out, 1) != fmi3OK) return 1;                                           \
        prefix##fmi3FreeInstance(c);                                                                                  \
    } while (0)
#endif

int main(int argc, char **argv) {
    if (argc != 4) return 2;
    int n = atoi(argv[3]);
    double rigid = 0.0, elastic = 0.0;
    RUN(rigid_, argv[1], rigid);
    RUN(elastic_, argv[2], elastic);
    printf("rigid=%.17g elastic=%.17g\n", rigid, elastic);
    return 0;
}
