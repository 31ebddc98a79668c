/* Minimal FMI 3.0 Co-Simulation and Model Exchange importer, independent of fmpy (see fmi2_harness.c).
 * usage: fmi3_harness <binary.so> <instantiation token> <n_steps>
 * ME is driven with a hand-written explicit Euler loop only to exercise the ME entry points. */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

static int n_errors_logged = 0;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    (void)category;
    (void)message;
    if (status >= fmi3Error) n_errors_logged++;
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
    LOAD(fmi3InstantiateCoSimulation) LOAD(fmi3InstantiateModelExchange) LOAD(fmi3FreeInstance)
    LOAD(fmi3EnterInitializationMode) LOAD(fmi3ExitInitializationMode) LOAD(fmi3Terminate) LOAD(fmi3DoStep)
    LOAD(fmi3GetFloat64) LOAD(fmi3SetFloat64) LOAD(fmi3GetFMUState) LOAD(fmi3SetFMUState) LOAD(fmi3FreeFMUState)
    LOAD(fmi3SerializedFMUStateSize) LOAD(fmi3SerializeFMUState) LOAD(fmi3DeserializeFMUState)
    LOAD(fmi3EnterContinuousTimeMode) LOAD(fmi3UpdateDiscreteStates) LOAD(fmi3SetTime) LOAD(fmi3SetContinuousStates)
    LOAD(fmi3GetContinuousStates) LOAD(fmi3GetContinuousStateDerivatives) LOAD(fmi3CompletedIntegratorStep)
    LOAD(fmi3GetNumberOfContinuousStates) LOAD(fmi3GetDirectionalDerivative) LOAD(fmi3Reset)

    fmi3Instance c = fmi3InstantiateCoSimulation("cs", argv[2], "", fmi3False, fmi3False, fmi3False, fmi3False, NULL,
                                                 0, NULL, logger, NULL);
    CHECK(c != NULL);
    const fmi3ValueReference vr_theta1 = 100, vr_energy = 404, vr_tau1 = 300, vr_dth1 = 200;
    fmi3Float64 x0 = 1.0, e0, e1, th, th2;
    CHECK(fmi3SetFloat64(c, &vr_theta1, 1, &x0, 1) == fmi3OK);
    CHECK(fmi3EnterInitializationMode(c, fmi3True, 1e-10, 0.0, fmi3False, 0.0) == fmi3OK);
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK);
    CHECK(fmi3GetFloat64(c, &vr_energy, 1, &e0, 1) == fmi3OK);
    int n = atoi(argv[3]);
    double t = 0.0, t_saved = 0.0, h = 0.01, last;
    fmi3Boolean ev, term, early;
    fmi3FMUState s = NULL, s2 = NULL;
    for (int k = 0; k < n; k++) {
        if (k == n / 2) {
            CHECK(fmi3GetFMUState(c, &s) == fmi3OK);
            t_saved = t; /* the same communication points give a bit-identical continuation */
        }
        CHECK(fmi3DoStep(c, t, h, fmi3True, &ev, &term, &early, &last) == fmi3OK);
        t += h;
        CHECK(last == t && !ev && !term && !early);
    }
    CHECK(fmi3GetFloat64(c, &vr_theta1, 1, &th, 1) == fmi3OK);
    CHECK(fmi3GetFloat64(c, &vr_energy, 1, &e1, 1) == fmi3OK);
    size_t size = 0;
    CHECK(fmi3SerializedFMUStateSize(c, s, &size) == fmi3OK);
    fmi3Byte *buf = (fmi3Byte *)malloc(size);
    CHECK(fmi3SerializeFMUState(c, s, buf, size) == fmi3OK);
    CHECK(fmi3DeserializeFMUState(c, buf, size, &s2) == fmi3OK);
    CHECK(fmi3SetFMUState(c, s2) == fmi3OK);
    t = t_saved;
    for (int k = n / 2; k < n; k++) {
        CHECK(fmi3DoStep(c, t, h, fmi3True, &ev, &term, &early, &last) == fmi3OK);
        t += h;
    }
    CHECK(fmi3GetFloat64(c, &vr_theta1, 1, &th2, 1) == fmi3OK);
    CHECK(memcmp(&th, &th2, sizeof th) == 0);
    /* fmusim's resume-from-file flow: a fresh instance, restore the serialized state, step (no initialization) */
    {
        fmi3Instance r = fmi3InstantiateCoSimulation("resumed", argv[2], "", fmi3False, fmi3False, fmi3False, fmi3False,
                                                     NULL, 0, NULL, logger, NULL);
        fmi3FMUState s3 = NULL;
        fmi3Float64 th3;
        CHECK(r != NULL);
        CHECK(fmi3DeserializeFMUState(r, buf, size, &s3) == fmi3OK);
        CHECK(fmi3SetFMUState(r, s3) == fmi3OK);
        CHECK(fmi3GetFloat64(r, &vr_theta1, 1, &th3, 1) == fmi3OK);
        double tr = t_saved;
        for (int k = n / 2; k < n; k++) {
            CHECK(fmi3DoStep(r, tr, h, fmi3True, &ev, &term, &early, &last) == fmi3OK);
            tr += h;
        }
        CHECK(fmi3GetFloat64(r, &vr_theta1, 1, &th3, 1) == fmi3OK);
        CHECK(memcmp(&th, &th3, sizeof th) == 0);
        CHECK(fmi3FreeFMUState(r, &s3) == fmi3OK);
        fmi3FreeInstance(r);
    }
    int before = n_errors_logged;
    fmi3Float64 nan = NAN;
    CHECK(fmi3SetFloat64(c, &vr_tau1, 1, &nan, 1) == fmi3Error);
    CHECK(fmi3DoStep(c, t, 0.0, fmi3True, &ev, &term, &early, &last) == fmi3Error);
    CHECK(fmi3GetFloat64(c, NULL, 1, NULL, 1) == fmi3Error);
    CHECK(fmi3DoStep(c, t, h, fmi3True, NULL, NULL, NULL, NULL) == fmi3Error);
    CHECK(n_errors_logged - before == 4);
    CHECK(fmi3Reset(c) == fmi3OK);
    CHECK(fmi3FreeFMUState(c, &s) == fmi3OK && s == NULL);
    CHECK(fmi3FreeFMUState(c, &s2) == fmi3OK);
    free(buf);
    fmi3FreeInstance(c);

    /* Model Exchange: explicit Euler on the ME entry points; d(theta1)/dt must equal omega1 */
    fmi3Instance m = fmi3InstantiateModelExchange("me", argv[2], "", fmi3False, fmi3False, NULL, logger);
    CHECK(m != NULL);
    size_t nx = 0;
    CHECK(fmi3GetNumberOfContinuousStates(m, &nx) == fmi3OK && nx >= 4 && nx <= 16);
    const fmi3ValueReference vr_om1 = (fmi3ValueReference)(100 + nx / 2); /* omega1 follows the positions */
    CHECK(fmi3SetFloat64(m, &vr_theta1, 1, &x0, 1) == fmi3OK);
    CHECK(fmi3EnterInitializationMode(m, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK);
    CHECK(fmi3ExitInitializationMode(m) == fmi3OK);
    fmi3Boolean a, b, cc, d, e;
    fmi3Float64 next;
    CHECK(fmi3UpdateDiscreteStates(m, &a, &b, &cc, &d, &e, &next) == fmi3OK);
    CHECK(fmi3EnterContinuousTimeMode(m) == fmi3OK);
    double x[16], dx[16];
    CHECK(fmi3GetContinuousStates(m, x, nx) == fmi3OK);
    for (int k = 0; k < 100; k++) {
        CHECK(fmi3GetContinuousStateDerivatives(m, dx, nx) == fmi3OK);
        for (size_t i = 0; i < nx; i++) x[i] += 1e-3 * dx[i];
        CHECK(fmi3SetTime(m, (k + 1) * 1e-3) == fmi3OK);
        CHECK(fmi3SetContinuousStates(m, x, nx) == fmi3OK);
        CHECK(fmi3CompletedIntegratorStep(m, fmi3True, &a, &b) == fmi3OK);
    }
    fmi3Float64 dth, om, seed = 1.0, sens;
    CHECK(fmi3GetFloat64(m, &vr_dth1, 1, &dth, 1) == fmi3OK);
    CHECK(fmi3GetFloat64(m, &vr_om1, 1, &om, 1) == fmi3OK);
    CHECK(dth == om);
    CHECK(fmi3GetDirectionalDerivative(m, &vr_dth1, 1, &vr_om1, 1, &seed, 1, &sens, 1) == fmi3OK && sens == 1.0);
    CHECK(fmi3Terminate(m) == fmi3OK);
    fmi3FreeInstance(m);
    printf("theta1=%.17g energy_drift=%.3e\n", th, fabs(e1 - e0));
    dlclose(lib);
    return 0;
}
