/* C importer of a pendulab controller FMU, linked statically with its sources (built with ASan/UBSan by
 * tests/fmu/test_controller_fmu.py): every entry point with a NULL instance, NULL arrays, bad values and in
 * wrong states, a normal sampled run, FMU state round trips, garbage states, then random call sequences.
 * Build: cc -DFMI_VERSION=2|3 -I <sources> ctrl_harness.c <sources>/ctrl_fmi<V>.c ctrl_core.c controller_*.c -lm
 * usage: ctrl_harness <n_random_calls>; exits 0 when every check passes (prints "ok <checks>"). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "controller.h"

#if FMI_VERSION == 2
#include "fmi2Functions.h"
#define OK fmi2OK
#define ERR fmi2Error
typedef fmi2Component Inst;
typedef fmi2ValueReference VR;
#else
#include "fmi3Functions.h"
#define OK fmi3OK
#define ERR fmi3Error
typedef fmi3Instance Inst;
typedef fmi3ValueReference VR;
#endif

static int checks = 0;
#define CHECK(cond)                                                                                                   \
    do {                                                                                                              \
        checks++;                                                                                                     \
        if (!(cond)) {                                                                                                \
            fprintf(stderr, "check failed: %s (line %d)\n", #cond, __LINE__);                                         \
            return 1;                                                                                                 \
        }                                                                                                             \
    } while (0)

static unsigned long rng = 88172645463325252UL;
static unsigned long next_rand(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}
static double edge_value(void) {
    static const double v[] = {0.0, -0.0, 1.0, -1.0, 3.14159, 1e300, -1e300, 1e-300, 0.01, 0.005};
    unsigned long r = next_rand() % 13;
    if (r == 10) return NAN;
    if (r == 11) return INFINITY;
    if (r == 12) return -INFINITY;
    return v[r];
}
static VR some_vr(void) {
    static const VR v[] = {CTRL_VR_TIME, CTRL_VR_X, CTRL_VR_X + CTRL_NX - 1, CTRL_VR_X + CTRL_NX, CTRL_VR_U,
                           CTRL_VR_U + CTRL_NU - 1, CTRL_VR_U + CTRL_NU, CTRL_VR_SAMPLE_TIME, 7, 0xFFFFFFFFu};
    return v[next_rand() % (sizeof(v) / sizeof(v[0]))];
}

#if FMI_VERSION == 2
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category, fmi2String message,
                   ...) {
    (void)env;
    (void)name;
    (void)status;
    (void)category;
    (void)message;
}
static const fmi2CallbackFunctions CB = {logger, calloc, free, NULL, NULL};
static Inst make(const char *name, const char *token) {
    return fmi2Instantiate(name, fmi2CoSimulation, token, "", &CB, fmi2False, fmi2False);
}
static int init(Inst c) {
    return fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != OK || fmi2EnterInitializationMode(c) != OK ||
           fmi2ExitInitializationMode(c) != OK;
}
#define GET(c, vr, n, v) fmi2GetReal(c, vr, n, v)
#define SET(c, vr, n, v) fmi2SetReal(c, vr, n, v)
#define STEP(c, t, h) fmi2DoStep(c, t, h, fmi2True)
#define GETSTATE(c, s) fmi2GetFMUstate(c, s)
#define SETSTATE(c, s) fmi2SetFMUstate(c, s)
#define FREESTATE(c, s) fmi2FreeFMUstate(c, s)
#define SERSIZE(c, s, n) fmi2SerializedFMUstateSize(c, s, n)
#define SERIALIZE(c, s, b, n) fmi2SerializeFMUstate(c, s, (fmi2Byte *)(b), n)
#define DESERIALIZE(c, b, n, s) fmi2DeSerializeFMUstate(c, (const fmi2Byte *)(b), n, s)
#define TERMINATE(c) fmi2Terminate(c)
#define FREE(c) fmi2FreeInstance(c)
typedef fmi2FMUstate State;
#else
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    (void)status;
    (void)category;
    (void)message;
}
static Inst make(const char *name, const char *token) {
    return fmi3InstantiateCoSimulation(name, token, "", fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL, logger, NULL);
}
static int init(Inst c) {
    return fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != OK || fmi3ExitInitializationMode(c) != OK;
}
#define GET(c, vr, n, v) fmi3GetFloat64(c, vr, n, v, n)
#define SET(c, vr, n, v) fmi3SetFloat64(c, vr, n, v, n)
static int STEP(Inst c, double t, double h) {
    fmi3Boolean a, b, e;
    fmi3Float64 last;
    return fmi3DoStep(c, t, h, fmi3True, &a, &b, &e, &last);
}
#define GETSTATE(c, s) fmi3GetFMUState(c, s)
#define SETSTATE(c, s) fmi3SetFMUState(c, s)
#define FREESTATE(c, s) fmi3FreeFMUState(c, s)
#define SERSIZE(c, s, n) fmi3SerializedFMUStateSize(c, s, n)
#define SERIALIZE(c, s, b, n) fmi3SerializeFMUState(c, s, (fmi3Byte *)(b), n)
#define DESERIALIZE(c, b, n, s) fmi3DeserializeFMUState(c, (const fmi3Byte *)(b), n, s)
#define TERMINATE(c) fmi3Terminate(c)
#define FREE(c) fmi3FreeInstance(c)
typedef fmi3FMUState State;
#endif

int main(int argc, char **argv) {
    long n_random = argc > 1 ? atol(argv[1]) : 1000;
    VR xs[CTRL_NX], us[CTRL_NU];
    double x[CTRL_NX], u[CTRL_NU], u2[CTRL_NU];
    const double h = CTRL_SAMPLE_TIME;
    for (int i = 0; i < CTRL_NX; i++) xs[i] = CTRL_VR_X + i;
    for (int i = 0; i < CTRL_NU; i++) us[i] = CTRL_VR_U + i;

    /* NULL instance everywhere: Error, never a crash */
    CHECK(GET(NULL, us, CTRL_NU, u) == ERR);
    CHECK(SET(NULL, xs, CTRL_NX, x) == ERR);
    CHECK(STEP(NULL, 0.0, h) == ERR);
    CHECK(TERMINATE(NULL) == ERR);
    CHECK(SETSTATE(NULL, NULL) == ERR);
    FREE(NULL);
    /* refused instantiations */
    CHECK(make(NULL, CTRL_TOKEN) == NULL);
    CHECK(make("", CTRL_TOKEN) == NULL);
    CHECK(make("c", "{not the token}") == NULL);
    CHECK(make("c", NULL) == NULL);

    Inst c = make("c", CTRL_TOKEN);
    CHECK(c != NULL);
#if FMI_VERSION == 2 /* a defined tolerance must be in (0, 1), as for the plant FMUs (the controller has no solver) */
    CHECK(fmi2SetupExperiment(c, fmi2True, NAN, 0.0, fmi2False, 0.0) == ERR);
    CHECK(fmi2SetupExperiment(c, fmi2True, 0.0, 0.0, fmi2False, 0.0) == ERR);
    CHECK(fmi2SetupExperiment(c, fmi2True, 1e-8, 0.0, fmi2False, 0.0) == OK);
#else
    CHECK(fmi3EnterInitializationMode(c, fmi3True, NAN, 0.0, fmi3False, 0.0) == ERR);
    CHECK(fmi3EnterInitializationMode(c, fmi3True, 1.5, 0.0, fmi3False, 0.0) == ERR);
#endif
    CHECK(GET(c, us, CTRL_NU, u) == ERR); /* outputs not before initialization */
    CHECK(STEP(c, 0.0, h) == ERR);        /* not before initialization */
    const VR vh = CTRL_VR_SAMPLE_TIME;
    double bad = -1.0;
    CHECK(SET(c, &vh, 1, &bad) == ERR);
    CHECK(SET(c, NULL, 1, &bad) == ERR);
    CHECK(SET(c, &vh, 1, NULL) == ERR);
    CHECK(SET(c, NULL, 0, NULL) == OK);
    CHECK(init(c) == 0);
    for (int i = 0; i < CTRL_NX; i++) x[i] = 0.1 * (i + 1);
    State saved = NULL;
    for (int k = 0; k < 300; k++) {
        x[0] = 0.3 * sin(0.05 * k);
        CHECK(SET(c, xs, CTRL_NX, x) == OK);
        CHECK(GET(c, us, CTRL_NU, u) == OK);
        for (int i = 0; i < CTRL_NU; i++) CHECK(isfinite(u[i]));
        if (k == 100) CHECK(GETSTATE(c, &saved) == OK);
        CHECK(STEP(c, k * h, h) == OK);
    }
    /* misuse in step mode */
    double nan_value = NAN;
    CHECK(SET(c, xs, 1, &nan_value) == ERR);
    CHECK(SET(c, us, 1, x) == ERR);  /* outputs are read-only */
    CHECK(SET(c, &vh, 1, x) == ERR); /* fixed parameter after initialization */
    VR unknown = 12345;
    CHECK(GET(c, &unknown, 1, u) == ERR);
    CHECK(GET(c, us, CTRL_NU, NULL) == ERR);
    CHECK(STEP(c, 1234.5, h) == ERR);  /* communication point is not the FMU's time: refused, instance usable */
    CHECK(STEP(c, 300 * h, -h) == ERR); /* negative step */
    CHECK(STEP(c, 300 * h, 0.0) == ERR); /* a step of size 0 (or -0, NaN, Inf): Error, as the plant FMUs */
    CHECK(STEP(c, 300 * h, -0.0) == ERR);
    CHECK(STEP(c, 300 * h, NAN) == ERR);
    CHECK(STEP(c, 300 * h, INFINITY) == ERR);
    CHECK(STEP(c, NAN, h) == ERR);
    CHECK(STEP(c, 300 * h, 1e300) == ERR); /* more samples than the work limit */
    CHECK(STEP(c, 300 * h, h) == OK);
    /* restart from the saved state (also from Error), replay bit-identically */
    CHECK(SETSTATE(c, saved) == OK);
    x[0] = 0.3 * sin(0.05 * 100);
    CHECK(SET(c, xs, CTRL_NX, x) == OK);
    CHECK(GET(c, us, CTRL_NU, u) == OK);
    size_t size = 0;
    CHECK(SERSIZE(c, saved, &size) == OK);
    CHECK(SERSIZE(c, saved, NULL) == ERR);
    unsigned char *blob = (unsigned char *)malloc(size);
    CHECK(blob != NULL);
    CHECK(SERIALIZE(c, saved, blob, size) == OK);
    CHECK(SERIALIZE(c, saved, blob, size - 1) == ERR);
    State back = NULL;
    CHECK(DESERIALIZE(c, blob, size, &back) == OK);
    CHECK(SETSTATE(c, back) == OK);
    CHECK(SET(c, xs, CTRL_NX, x) == OK);
    CHECK(GET(c, us, CTRL_NU, u2) == OK);
    CHECK(memcmp(u, u2, sizeof(u)) == 0);
    blob[3] ^= 0x5A; /* a foreign / corrupted state */
    State junk = NULL;
    CHECK(DESERIALIZE(c, blob, size, &junk) == ERR);
    CHECK(DESERIALIZE(c, blob, size / 2, &junk) == ERR);
    CHECK(DESERIALIZE(c, NULL, size, &junk) == ERR);
    CHECK(SETSTATE(c, NULL) == ERR);
    free(blob);
    CHECK(FREESTATE(c, &back) == OK);
    CHECK(FREESTATE(c, &saved) == OK);
    CHECK(FREESTATE(c, NULL) == ERR);
    State direct = NULL; /* the state itself instead of its address (an importer bug): freed, never dereferenced */
    CHECK(GETSTATE(c, &direct) == OK);
    CHECK(FREESTATE(c, (State *)direct) == OK);

    /* random call sequences with edge values, NULL arrays and out-of-range references: never a crash */
    State good = NULL;
    CHECK(GETSTATE(c, &good) == OK);
    const VR vt = CTRL_VR_TIME;
    for (long n = 0; n < n_random; n++) {
        VR vr[3] = {some_vr(), some_vr(), some_vr()};
        double v[3] = {edge_value(), edge_value(), edge_value()};
        size_t m = next_rand() % 4;
        int null_vr = next_rand() % 8 == 0, null_v = next_rand() % 8 == 0;
        switch (next_rand() % 6) {
        case 0: (void)SET(c, null_vr ? NULL : vr, m, null_v ? NULL : v); break;
        case 1: (void)GET(c, null_vr ? NULL : vr, m, null_v ? NULL : v); break;
        case 2: {
            double t = 0.0;
            if (GET(c, &vt, 1, &t) == OK) (void)STEP(c, t, fabs(v[0]) < 1.0 ? fabs(v[0]) : h);
            break;
        }
        case 3: {
            State s = NULL;
            if (GETSTATE(c, &s) == OK) {
                (void)SETSTATE(c, s);
                (void)FREESTATE(c, &s);
            }
            break;
        }
        case 4: (void)(next_rand() % 2 ? SETSTATE(c, good) : SET(c, xs, CTRL_NX, x)); break; /* back to a good state */
        default: (void)STEP(c, v[1], v[2]); break;
        }
    }
    CHECK(SETSTATE(c, good) == OK); /* still usable after the random calls */
    CHECK(SET(c, xs, CTRL_NX, x) == OK);
    CHECK(GET(c, us, CTRL_NU, u2) == OK);
    CHECK(FREESTATE(c, &good) == OK);
    (void)TERMINATE(c);
    FREE(c);
    printf("ok %d\n", checks);
    return 0;
}
