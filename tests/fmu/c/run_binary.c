/* Portable FMI Co-Simulation runner (POSIX dlopen or Windows LoadLibrary), for the binaries of other platforms
 * run under an emulator (qemu-user, wine). Build with -DFMI_VERSION=2|3 and the FMU's sources/ on the include path.
 * usage: run_binary <library> <token> <n_steps>; prints "theta1=<value> energy=<value>" after n steps of 0.01 s
 * from theta1 = 1 rad (tolerance 1e-10), exit 0 on success. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#define LOAD_LIBRARY(path) ((void *)LoadLibraryA(path))
#define GET_SYMBOL(lib, name) ((void *)GetProcAddress((HMODULE)(lib), name))
#else
#include <dlfcn.h>
#define LOAD_LIBRARY(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define GET_SYMBOL(lib, name) dlsym(lib, name)
#endif

#define FAIL(msg)                                                                                                     \
    do {                                                                                                              \
        fprintf(stderr, "%s (line %d)\n", msg, __LINE__);                                                             \
        return 1;                                                                                                     \
    } while (0)

#if FMI_VERSION == 2
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)name;
    (void)category;
    if (status >= fmi2Error) fprintf(stderr, "FMU: %s\n", message);
}
#else
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    (void)category;
    if (status >= fmi3Error) fprintf(stderr, "FMU: %s\n", message);
}
#endif

#define LOAD(name)                                                                                                    \
    name##TYPE *name;                                                                                                 \
    {                                                                                                                 \
        void *sym = GET_SYMBOL(lib, #name);                                                                           \
        if (sym == NULL) FAIL("missing " #name);                                                                      \
        memcpy(&name, &sym, sizeof sym);                                                                              \
    }

int main(int argc, char **argv) {
    if (argc != 4) return 2;
    void *lib = LOAD_LIBRARY(argv[1]);
    if (lib == NULL) FAIL("cannot load the library");
    int n = atoi(argv[3]);
    double theta1 = 0.0, energy = 0.0;
#if FMI_VERSION == 2
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode) LOAD(fmi2ExitInitializationMode)
    LOAD(fmi2DoStep) LOAD(fmi2GetReal) LOAD(fmi2SetReal) LOAD(fmi2FreeInstance)
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("run", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
    const fmi2ValueReference vr[2] = {100, 404};
    fmi2Real x0 = 1.0, out[2];
    if (c == NULL) FAIL("instantiate failed");
    if (fmi2SetReal(c, vr, 1, &x0) != fmi2OK || fmi2SetupExperiment(c, fmi2True, 1e-10, 0.0, fmi2False, 0.0) != fmi2OK ||
        fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK)
        FAIL("initialization failed");
    for (int k = 0; k < n; k++)
        if (fmi2DoStep(c, k * 0.01, 0.01, fmi2True) != fmi2OK) FAIL("step failed");
    if (fmi2GetReal(c, vr, 2, out) != fmi2OK) FAIL("get failed");
    fmi2FreeInstance(c);
#else
    LOAD(fmi3InstantiateCoSimulation) LOAD(fmi3EnterInitializationMode) LOAD(fmi3ExitInitializationMode) LOAD(fmi3DoStep)
    LOAD(fmi3GetFloat64) LOAD(fmi3SetFloat64) LOAD(fmi3FreeInstance)
    fmi3Instance c = fmi3InstantiateCoSimulation("run", argv[2], "", fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                                                 NULL, logger, NULL);
    const fmi3ValueReference vr[2] = {100, 404};
    fmi3Float64 x0 = 1.0, out[2], last;
    fmi3Boolean ev, term, early;
    if (c == NULL) FAIL("instantiate failed");
    if (fmi3SetFloat64(c, vr, 1, &x0, 1) != fmi3OK ||
        fmi3EnterInitializationMode(c, fmi3True, 1e-10, 0.0, fmi3False, 0.0) != fmi3OK ||
        fmi3ExitInitializationMode(c) != fmi3OK)
        FAIL("initialization failed");
    for (int k = 0; k < n; k++)
        if (fmi3DoStep(c, k * 0.01, 0.01, fmi3True, &ev, &term, &early, &last) != fmi3OK) FAIL("step failed");
    if (fmi3GetFloat64(c, vr, 2, out, 2) != fmi3OK) FAIL("get failed");
    fmi3FreeInstance(c);
#endif
    theta1 = out[0];
    energy = out[1];
    printf("theta1=%.17g energy=%.17g\n", theta1, energy);
    return 0;
}
