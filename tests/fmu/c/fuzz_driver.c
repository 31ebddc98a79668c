/* Standalone FMI call-sequence fuzzer, linked directly with the FMU sources (for AddressSanitizer and
 * UndefinedBehaviorSanitizer builds: no Python, no dlopen). The same kinds of sequences as
 * benchmarks/fuzz_fmi.py: random calls in random order with edge values (NaN, +-inf, 0, negative, tiny and
 * huge steps, invalid value references, NULL pointers, corrupted/garbage serialized states), on
 * Co-Simulation and Model Exchange instances.
 * build: cc -std=c99 -DFUZZ_FMI=2|3 -I<sources> fuzz_driver.c fmi2.c|fmi3.c fmu_core.c ode_solver.c model_functions.c -lm
 * usage: fuzz_driver <token> <n_sequences> <length> <seed>
 * Prints "sequences=.. calls=.. ok=.. discard=.. error=.." and exits 0; 1 on an invalid status or an
 * Error without a logged message; a memory error aborts under the sanitizers. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if FUZZ_FMI == 3
#include "fmi3Functions.h"
#else
#include "fmi2Functions.h"
#endif
#include "model.h"

static unsigned long long rng_state = 1;
static unsigned rnd(void) { /* xorshift64* */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (unsigned)((rng_state * 2685821657736338717ULL) >> 32);
}
static int pick(int n) { return (int)(rnd() % (unsigned)n); }
static double uni(double a, double b) { return a + (b - a) * (rnd() / 4294967296.0); }

static double edge(void) {
    static const double v[] = {0.0, -0.0, -1.0, 1e-300, -1e-300, 5e-324, 1e300, -1e300, 1.7976931348623157e308,
                               1e-15, 0.5, 1.0, 2.0, 10.0, 0.01};
    int k = pick(18);
    if (k == 15) return NAN;
    if (k == 16) return INFINITY;
    if (k == 17) return -INFINITY;
    return v[k];
}
static double value(void) { return pick(2) ? edge() : uni(-3.0, 3.0); }
static double step(void) {
    static const double v[] = {0.01, 0.01, 0.01, 0.01, 0.001, 0.1, 1e-300, 5e-324, 1e-15, 1e-12, 0.0, -0.01, 1e300, 1e6};
    int k = pick(16);
    if (k == 14) return NAN;
    if (k == 15) return INFINITY;
    return v[k];
}
static unsigned vref(void) {
    static const unsigned bad[] = {1, 99, 150, 299, 350, 499, 899, 903, 9999, 4294967295u};
    int k = pick(10);
    if (k < 8) {
        switch (pick(7)) {
        case 0: return MODEL_VR_TIME;
        case 1: return MODEL_VR_X + (unsigned)pick(MODEL_NX);
        case 2: return MODEL_VR_DX + (unsigned)pick(MODEL_NX);
        case 3: return MODEL_VR_U + (unsigned)pick(MODEL_NU);
        case 4: return MODEL_VR_Y + (unsigned)pick(MODEL_NY);
        case 5: return MODEL_VR_P + (unsigned)pick(MODEL_NP);
        default: return MODEL_VR_TOL + (unsigned)pick(3);
        }
    }
    return bad[pick(10)];
}

static int logged = 0;
static long n_calls = 0, n_status[5] = {0, 0, 0, 0, 0};

static int check(int status, int line) {
    n_calls++;
    if (status < 0 || status > 4) {
        fprintf(stderr, "invalid status %d (line %d)\n", status, line);
        exit(1);
    }
    if (status >= 2 && !logged) {
        fprintf(stderr, "status %d without a logged message (line %d)\n", status, line);
        exit(1);
    }
    n_status[status]++;
    logged = 0;
    return status;
}
#define CALL(expr) (logged = 0, check((int)(expr), __LINE__))

#if FUZZ_FMI == 3
typedef fmi3Instance Inst;
typedef fmi3FMUState State;
typedef fmi3Byte Byte;
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    (void)category;
    if (message == NULL || message[0] == '\0') return;
    if (status >= fmi3Discard) logged = 1;
}
#define P(name) fmi3##name
#define STATE_FN(name) fmi3##name##FMUState
#define SIZE_FN fmi3SerializedFMUStateSize
#define SERIALIZE_FN fmi3SerializeFMUState
#else
typedef fmi2Component Inst;
typedef fmi2FMUstate State;
typedef fmi2Byte Byte;
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    char buf[1024];
    va_list ap;
    (void)env;
    (void)name;
    (void)category;
    va_start(ap, message);
    vsnprintf(buf, sizeof buf, message, ap);
    va_end(ap);
    if (buf[0] != '\0' && status >= fmi2Discard) logged = 1;
}
static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
#define P(name) fmi2##name
#define STATE_FN(name) fmi2##name##FMUstate
#define SIZE_FN fmi2SerializedFMUstateSize
#define SERIALIZE_FN fmi2SerializeFMUstate
#endif

static Inst instantiate(const char *token, int cs) {
#if FUZZ_FMI == 3
    if (cs) return fmi3InstantiateCoSimulation("fuzz", token, NULL, 0, 0, 0, 0, NULL, 0, NULL, logger, NULL);
    return fmi3InstantiateModelExchange("fuzz", token, NULL, 0, 0, NULL, logger);
#else
    return fmi2Instantiate("fuzz", cs ? fmi2CoSimulation : fmi2ModelExchange, token, "", &callbacks, 0, 0);
#endif
}

static double now(Inst c) {
    unsigned vr = MODEL_VR_TIME;
    double t = 0.0;
    int saved = logged;
#if FUZZ_FMI == 3
    if (fmi3GetFloat64(c, &vr, 1, &t, 1) != fmi3OK) t = 0.0;
#else
    if (fmi2GetReal(c, &vr, 1, &t) != fmi2OK) t = 0.0;
#endif
    logged = saved;
    return t;
}

static void sequence(const char *token, int cs, int length) {
    Inst c = instantiate(token, cs);
    if (c == NULL) {
        fprintf(stderr, "instantiation failed\n");
        exit(1);
    }
    State st[3] = {NULL, NULL, NULL};
    Byte *blob[3] = {NULL, NULL, NULL};
    size_t blob_size[3] = {0, 0, 0};
    for (int k = 0; k < length; k++) {
        unsigned vr[4];
        double v[MODEL_NX + 2], out[MODEL_NX + MODEL_NY + 2];
        int n = 1 + pick(3), s = pick(3);
        for (int i = 0; i < 4; i++) vr[i] = vref();
        for (int i = 0; i < MODEL_NX + 2; i++) v[i] = pick(6) ? uni(0.5, 1.5) : value();
        switch (pick(24)) {
        case 0:
        case 1: {
            double t = pick(5) ? now(c) : value(), h = step();
#if FUZZ_FMI == 3
            fmi3Boolean a, b, e;
            double last;
            CALL(fmi3DoStep(c, t, h, 1, &a, &b, &e, &last));
#else
            CALL(fmi2DoStep(c, t, h, 1));
#endif
            break;
        }
        case 2:
            for (int i = 0; i < n; i++) v[i] = value();
#if FUZZ_FMI == 3
            CALL(fmi3SetFloat64(c, vr, (size_t)n, v, (size_t)n));
#else
            CALL(fmi2SetReal(c, vr, (size_t)n, v));
#endif
            break;
        case 3:
#if FUZZ_FMI == 3
            CALL(fmi3GetFloat64(c, vr, (size_t)n, out, (size_t)n));
#else
            CALL(fmi2GetReal(c, vr, (size_t)n, out));
#endif
            break;
        case 4: {
            int sv = pick(4) - 1;
            unsigned r = pick(4) ? MODEL_VR_SOLVER : 3;
#if FUZZ_FMI == 3
            CALL(fmi3SetInt32(c, &r, 1, &sv, 1));
#else
            CALL(fmi2SetInteger(c, &r, 1, &sv));
#endif
            break;
        }
        case 5:
#if FUZZ_FMI == 3
            CALL(fmi3EnterInitializationMode(c, pick(2), pick(3) ? 1e-8 : value(), pick(3) ? 0.0 : value(), 0, 0.0));
#else
            if (CALL(fmi2SetupExperiment(c, pick(2), pick(3) ? 1e-8 : value(), pick(3) ? 0.0 : value(), 0, 0.0)) == 0)
                CALL(fmi2EnterInitializationMode(c));
#endif
            break;
        case 6: CALL(P(ExitInitializationMode)(c)); break;
        case 7:
            if (pick(2)) CALL(P(Terminate)(c));
            else CALL(P(Reset)(c));
            break;
        case 8: CALL(STATE_FN(Get)(c, &st[s])); break;
        case 9: CALL(STATE_FN(Set)(c, st[s])); break;
        case 10: CALL(STATE_FN(Free)(c, &st[s])); break;
        case 11: {
            size_t size = 0;
            if (CALL(SIZE_FN(c, st[s], &size)) == 0) {
                free(blob[s]);
                blob[s] = (Byte *)malloc(size);
                blob_size[s] = size;
                if (CALL(SERIALIZE_FN(c, st[s], blob[s], size)) != 0) blob_size[s] = 0;
            }
            break;
        }
        case 12:
        case 13: { /* deserialize a saved blob, a corrupted copy, or garbage of the right or a wrong size */
            size_t size = blob[s] ? blob_size[s] : 64;
            size_t alloc = size + 16;
            Byte *b = (Byte *)calloc(alloc, 1);
            if (blob[s]) memcpy(b, blob[s], blob_size[s]);
            int form = pick(6);
            if (form == 1 && size >= 8) { /* overwrite an aligned double-sized field */
                double bad = value();
                memcpy(b + 8 * (size_t)pick((int)(size / 8)), &bad, sizeof bad);
            } else if (form == 2) {
                for (size_t i = 0; i < size; i++) b[i] = (Byte)rnd();
            } else if (form == 3) {
                b[pick((int)size)] ^= (Byte)(1u << pick(8));
            } else if (form == 4) {
                size = (size_t)pick((int)alloc);
            }
#if FUZZ_FMI == 3
            CALL(fmi3DeserializeFMUState(c, form == 5 ? NULL : b, size, &st[s]));
#else
            CALL(fmi2DeSerializeFMUstate(c, form == 5 ? NULL : b, size, &st[s]));
#endif
            free(b);
            break;
        }
        case 14: {
            unsigned unk = vref(), kn = vref();
            double seed = value(), sens;
#if FUZZ_FMI == 3
            CALL(fmi3GetDirectionalDerivative(c, &unk, 1, &kn, 1, &seed, 1, &sens, 1));
#else
            CALL(fmi2GetDirectionalDerivative(c, &unk, 1, &kn, 1, &seed, &sens));
#endif
            break;
        }
        case 15: CALL(P(EnterEventMode)(c)); break;
        case 16: CALL(P(EnterContinuousTimeMode)(c)); break;
        case 17: CALL(P(SetTime)(c, pick(3) ? now(c) + 1e-3 : value())); break;
        case 18: CALL(P(SetContinuousStates)(c, v, pick(6) ? MODEL_NX : (size_t)pick(MODEL_NX + 2))); break;
        case 19:
#if FUZZ_FMI == 3
            CALL(fmi3GetContinuousStateDerivatives(c, out, pick(6) ? MODEL_NX : (size_t)pick(MODEL_NX + 2)));
#else
            CALL(fmi2GetDerivatives(c, out, pick(6) ? MODEL_NX : (size_t)pick(MODEL_NX + 2)));
#endif
            break;
        case 20: {
#if FUZZ_FMI == 3
            fmi3Boolean a, b;
            CALL(fmi3CompletedIntegratorStep(c, 1, &a, pick(5) ? &b : NULL));
#else
            fmi2Boolean a, b;
            CALL(fmi2CompletedIntegratorStep(c, 1, &a, pick(5) ? &b : NULL));
#endif
            break;
        }
        case 21: {
#if FUZZ_FMI == 3
            fmi3Boolean a[5];
            double next;
            CALL(fmi3UpdateDiscreteStates(c, &a[0], &a[1], &a[2], &a[3], pick(3) ? &a[4] : NULL, &next));
#else
            fmi2EventInfo info;
            CALL(fmi2NewDiscreteStates(c, pick(4) ? &info : NULL));
#endif
            CALL(P(GetContinuousStates)(c, out, pick(6) ? MODEL_NX : 1));
            CALL(P(GetNominalsOfContinuousStates)(c, out, MODEL_NX));
            CALL(P(GetEventIndicators)(c, out, (size_t)pick(2)));
            break;
        }
        case 22: { /* NULL where a pointer is expected */
            size_t size;
#if FUZZ_FMI == 3
            CALL(fmi3GetFloat64(c, NULL, 2, NULL, 2));
            CALL(fmi3SetFloat64(c, NULL, 2, NULL, 2));
            CALL(fmi3GetFMUState(c, NULL));
            CALL(fmi3SerializedFMUStateSize(c, NULL, &size));
            CALL(fmi3SerializeFMUState(c, st[s], NULL, 10));
            CALL(fmi3DeserializeFMUState(c, NULL, 100, NULL));
            fmi3Boolean a, b, e;
            CALL(fmi3DoStep(c, now(c), 0.01, 1, &a, &b, &e, NULL));
            CALL(fmi3GetDirectionalDerivative(c, NULL, 1, NULL, 1, NULL, 1, NULL, 1));
            CALL(fmi3SetDebugLogging(c, 1, 2, NULL));
            CALL(fmi3GetNumberOfContinuousStates(c, NULL));
#else
            CALL(fmi2GetReal(c, NULL, 2, NULL));
            CALL(fmi2SetReal(c, NULL, 2, NULL));
            CALL(fmi2GetFMUstate(c, NULL));
            CALL(fmi2SerializedFMUstateSize(c, NULL, &size));
            CALL(fmi2SerializeFMUstate(c, st[s], NULL, 10));
            CALL(fmi2DeSerializeFMUstate(c, NULL, 100, NULL));
            CALL(fmi2GetDirectionalDerivative(c, NULL, 1, NULL, 1, NULL, NULL));
            CALL(fmi2SetDebugLogging(c, 1, 2, NULL));
            CALL(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, NULL));
            fmi2Status status;
            CALL(fmi2GetStatus(c, fmi2DoStepStatus, &status));
#endif
            CALL(P(SetContinuousStates)(c, NULL, MODEL_NX));
            CALL(P(GetContinuousStates)(c, NULL, MODEL_NX));
            break;
        }
        default: {
            const char *cats[] = {"logCalls", "nonsense", NULL};
            CALL(P(SetDebugLogging)(c, pick(2), (size_t)pick(4), cats));
            break;
        }
        }
    }
    for (int i = 0; i < 3; i++) {
        CALL(STATE_FN(Free)(c, &st[i]));
        free(blob[i]);
    }
    P(FreeInstance)(c);
}

int main(int argc, char **argv) {
    if (argc != 5) return 2;
    int n = atoi(argv[2]), length = atoi(argv[3]);
    rng_state = 0x9E3779B97F4A7C15ULL ^ (unsigned long long)strtoull(argv[4], NULL, 10);
    for (int i = 0; i < n; i++) sequence(argv[1], i % 2 == 0, length);
    P(FreeInstance)(NULL);
    printf("sequences=%d calls=%ld ok=%ld warning=%ld discard=%ld error=%ld fatal=%ld\n", n, n_calls, n_status[0],
           n_status[1], n_status[2], n_status[3], n_status[4]);
    return 0;
}
