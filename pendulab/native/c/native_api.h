/* Entry points of the native library of one model kind (called from Python through ctypes).
 *
 * The library is ode_solver.c + ode_loop.c + this file + the CasADi-generated model functions
 * (the same model_casadi.c an FMU of the same kind ships). Only the functions below are
 * exported; everything else has hidden visibility. No global mutable state: every call
 * keeps its CasADi work arrays on its own stack, so calls may run concurrently.
 */
#ifndef PENDULAB_NATIVE_API_H
#define PENDULAB_NATIVE_API_H

#include "ode_loop.h"

#if defined(_WIN32)
#define NATIVE_API __declspec(dllexport)
#elif defined(__GNUC__)
#define NATIVE_API __attribute__((visibility("default")))
#else
#define NATIVE_API
#endif

/* Bumped whenever a signature or OdeLoopStats changes; the Python side checks it. */
#define PENDULAB_NATIVE_ABI 1

NATIVE_API int pendulab_native_abi(void);

/* Sizes of the model and of OdeLoopStats [bytes]; any pointer may be NULL. */
NATIVE_API void pendulab_native_sizes(int *nx, int *nu, int *np, int *stats_bytes);

/* ode_run_grid of the model over t_grid (see ode_loop.h): method ODE_DOPRI5 (0) or ODE_RODAS4 (1). */
NATIVE_API int pendulab_native_run(int method, double rtol, double atol, double h_max, long max_steps, double h0,
                                   const double *t_grid, int n_grid, const double *u, int u_rows, const double *p,
                                   const double *x0, double *x_out, OdeLoopStats *stats);

NATIVE_API const char *pendulab_native_error_string(int code);

/* One evaluation of xdot = f(x, u, p), and of the dense column-major df/dx. */
NATIVE_API int pendulab_native_rhs(const double *x, const double *u, const double *p, double *xdot);
NATIVE_API int pendulab_native_jac(const double *x, const double *u, const double *p, double *J);

/* n_calls evaluations of f(x, u, p) for timing: path 0 calls the generated function directly with its
 * work arrays set up once (a bare call); path 1 goes through the callback chain the solver uses. */
NATIVE_API int pendulab_native_rhs_repeat(int path, long n_calls, const double *x, const double *u, const double *p,
                                          double *xdot);

#endif
