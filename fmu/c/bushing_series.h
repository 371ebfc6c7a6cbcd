/* A channel's layers in series over one step (docs/element.md), inside the kernel
 * (bushing_kernel.c): each layer's law (elastic 2µε(1+βε²), the memory's stress, B(ε − ε_c)
 * with B = m Σ g_j e^{−λ_j h} + c_v/h, Berg friction on the branch either side of the committed
 * strain), a layer alone with the drive, and the series equations σ_k(ε_k) = (2c_k/S_k) F,
 * Σ ε_k/c_k + C_b F = x: one Newton over the N + 1 unknowns, or its fallback, the nested
 * bracketed Newton. SI units; the state layout of bushing_kernel.h. */
#ifndef BUSHING_SERIES_H
#define BUSHING_SERIES_H

#include <stddef.h>

#include "bushing_kernel.h"

typedef struct {
    double two_mu, beta, b;          /* 2µ, β, B */
    double smax, ehalf_smax, ehalf;  /* friction: σ_fmax (0: none), ε½/σ_fmax, ε½ */
} bs_law;

/* one layer during a step: its law (the friction branches either side of the committed strain,
 * [0] moving down, [1] moving up) and the series solve's iterate. Scratch, in the work buffer. */
typedef struct {
    double eps_c, sig_c, dir;  /* committed strain, friction stress, direction (−1, 0, +1) */
    double z;                  /* Σ m g_j e^{−λ_j h} z_j: the memory's stress */
    double p, ip, c, ic;       /* p = 2c/S, 1/p, c and 1/c */
    double er[2], sr[2], num[2], d0[2];  /* each branch's reversal point, σ_fmax − sσ_r, d_0 */
    double eps, r, inv;        /* the iterate, its correction (σ − pF)/σ', 1/σ' there */
    int up;                    /* the iterate's branch */
} bs_layer;
#define BS_LAYER_DOUBLES ((sizeof(bs_layer) + sizeof(double) - 1) / sizeof(double))

static inline double bs_larger(double a, double b) { return a > b ? a : b; }

/* a layer alone with the drive x (no bulk spring): its load (N, N·m) and its state after the
 * step into `out` (pc: the layer's 2c/S, S/(2c), c, 1/c; gd: m g_j e^{−λ_j h}; decay: e^{−λ_j h}) */
double bs_direct(const bs_law *law, const double *layer, double *out, double x, const double *pc,
                 const double *gd, const double *decay, int J);

/* the n layers' laws for the step from their committed states (`layer`, layer_size apart;
 * pc: each layer's 2c/S, S/(2c), c, 1/c) */
void bs_prepare(bs_layer *L, int n, const bs_law *law, const double *layer, size_t layer_size,
                const double *pc, const double *gd, int J);

/* the n layers' states after the step, ending at their strains L[k].eps, into `out` (may be
 * `layer`) */
void bs_commit(const bs_layer *L, int n, const double *layer, double *out, size_t layer_size,
               const double *decay, int J);

/* The series equations of a channel of n layers (L, prepared; `layer` its first layer's state,
 * layer_size apart), bulk compliance cb, drive x: the load in *load (in: the committed one) and
 * each L[k].eps. bs_newton: 0 when converged, 1 when the caller must fall back to bs_nested;
 * bs_nested: 0, or 1 with a sentence in text. `count` (if not NULL) counts law evaluations. */
int bs_newton(const bs_law *law, bs_layer *L, const double *layer, size_t layer_size, int n,
              double cb, double x, double ratio, double scale, double *load, long *count);
int bs_nested(const bs_law *law, bs_layer *L, int n, double cb, double x, double scale,
              double *load, long *count, char *text, size_t length);

#endif
