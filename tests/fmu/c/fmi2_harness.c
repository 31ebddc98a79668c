/* Minimal FMI 2.0 Co-Simulation importer, independent of fmpy: dlopen the binary, drive it through
 * the standard entry points, check results and misuse handling. Run under valgrind to check memory.
 * usage: fmi2_harness <binary.so> <guid> <n_steps>
 * Prints "theta1=<value> energy_drift=<value>" and exits 0 when every check passes. */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

static int n_errors_logged = 0;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)name;
    (void)category;
    va_list ap;
    va_start(ap, message);
    if (status >= fmi2Error) n_errors_logged++;
    va_end(ap);
}

#define LOAD(name)                                                                                                    \
    name##TYPE *name = (name##TYPE *)dlsym(lib, #name);                                                               \
    if (!name) {                                                                                                      \
        fprintf(stderr, "missing %s\n", #name);                                                                       \
        return 2;                                                                                                     \
    }

#define CHECK(cond)                                                                                                   \
    if (!(cond)) {                                                                                                    \
        fprintf(stderr, "check failed: %s (line %d)\n", #cond, __LINE__);                                             \
        return 1;                                                                                                     \
    }

int main(int argc, char **argv) {
    if (argc != 4) return 2;
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 2;
    }
    LOAD(fmi2Instantiate) LOAD(fmi2FreeInstance) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2Terminate) LOAD(fmi2DoStep) LOAD(fmi2GetReal) LOAD(fmi2SetReal)
    LOAD(fmi2GetFMUstate) LOAD(fmi2SetFMUstate) LOAD(fmi2FreeFMUstate) LOAD(fmi2SerializedFMUstateSize)
    LOAD(fmi2SerializeFMUstate) LOAD(fmi2DeSerializeFMUstate) LOAD(fmi2GetVersion)

    CHECK(strcmp(fmi2GetVersion(), "2.0") == 0);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("harness", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
    CHECK(c != NULL);
    CHECK(fmi2Instantiate("bad", fmi2CoSimulation, "{wrong}", "", &cb, fmi2False, fmi2False) == NULL);
    const fmi2ValueReference vr_theta1 = 100, vr_energy = 404, vr_tau1 = 300;
    fmi2Real x0 = 1.0;
    CHECK(fmi2SetReal(c, &vr_theta1, 1, &x0) == fmi2OK);
    CHECK(fmi2SetupExperiment(c, fmi2True, 1e-10, 0.0, fmi2False, 0.0) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK);
    fmi2Real e0, e1, th;
    CHECK(fmi2GetReal(c, &vr_energy, 1, &e0) == fmi2OK);
    int n = atoi(argv[3]);
    double t = 0.0, t_saved = 0.0, h = 0.01;
    fmi2FMUstate s = NULL;
    for (int k = 0; k < n; k++) {
        if (k == n / 2) {
            CHECK(fmi2GetFMUstate(c, &s) == fmi2OK);
            t_saved = t; /* the same communication points give a bit-identical continuation */
        }
        CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK);
        t += h;
    }
    CHECK(fmi2GetReal(c, &vr_theta1, 1, &th) == fmi2OK);
    CHECK(fmi2GetReal(c, &vr_energy, 1, &e1) == fmi2OK);
    /* serialize the mid-run state, restore it, redo the second half: bit-identical */
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK);
    fmi2Byte *buf = (fmi2Byte *)malloc(size);
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK);
    fmi2FMUstate s2 = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK);
    CHECK(fmi2SetFMUstate(c, s2) == fmi2OK);
    t = t_saved;
    for (int k = n / 2; k < n; k++) {
        CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK);
        t += h;
    }
    fmi2Real th2;
    CHECK(fmi2GetReal(c, &vr_theta1, 1, &th2) == fmi2OK);
    CHECK(memcmp(&th, &th2, sizeof th) == 0);
    /* fmusim's resume-from-file flow: a fresh instance, restore the serialized state, step (no initialization) */
    {
        fmi2Component r = fmi2Instantiate("resumed", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
        fmi2FMUstate s3 = NULL;
        fmi2Real th3;
        CHECK(r != NULL);
        CHECK(fmi2DeSerializeFMUstate(r, buf, size, &s3) == fmi2OK);
        CHECK(fmi2SetFMUstate(r, s3) == fmi2OK);
        CHECK(fmi2GetReal(r, &vr_theta1, 1, &th3) == fmi2OK);
        double tr = t_saved;
        for (int k = n / 2; k < n; k++) {
            CHECK(fmi2DoStep(r, tr, h, fmi2True) == fmi2OK);
            tr += h;
        }
        CHECK(fmi2GetReal(r, &vr_theta1, 1, &th3) == fmi2OK);
        CHECK(memcmp(&th, &th3, sizeof th) == 0);
        CHECK(fmi2FreeFMUstate(r, &s3) == fmi2OK);
        fmi2FreeInstance(r);
    }
    /* misuse: error status and a logged message, never a crash */
    int before = n_errors_logged;
    fmi2Real nan = NAN;
    CHECK(fmi2SetReal(c, &vr_tau1, 1, &nan) == fmi2Error);
    CHECK(fmi2DoStep(c, t, -1.0, fmi2True) == fmi2Error);
    CHECK(fmi2GetReal(c, NULL, 1, NULL) == fmi2Error);
    CHECK(fmi2GetReal(NULL, &vr_theta1, 1, &th) == fmi2Error);
    CHECK(n_errors_logged - before == 3);
    CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK);
    CHECK(fmi2Terminate(c) == fmi2OK);
    CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2Error);
    CHECK(fmi2FreeFMUstate(c, &s) == fmi2OK && s == NULL);
    CHECK(fmi2FreeFMUstate(c, &s2) == fmi2OK);
    free(buf);
    fmi2FreeInstance(c);
    printf("theta1=%.17g energy_drift=%.3e\n", th, fabs(e1 - e0));
    dlclose(lib);
    return 0;
}
