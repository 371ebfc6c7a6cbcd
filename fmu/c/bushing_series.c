/* A channel's layers in series over one step: see bushing_series.h and docs/element.md. */
#include "bushing_series.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MAX_ITERATIONS 200
#define NEWTON_ITERATIONS 40   /* the one-level Newton's; beyond, the nested solve */
#define NEWTON_TOLERANCE 1e-13 /* its relative steps in the load and the strains */
#define LAYER_TOLERANCE 2e-15  /* nested solve: relative step in a layer's strain, a few ulp */
#define LOAD_TOLERANCE 1e-14   /* nested solve: relative step in the channel's load */
#define ROUNDING 8.0 * 2.220446049250313e-16 /* a residual's rounding: 8 ulp of its terms' size */

/* ------------------------------------------------------------------------------------------ */
/* one layer's law over a step */

/* the layer's stress σ(ε) and slope dσ/dε on branch `up`: elastic, memory (its stress at ε_c plus
 * B(ε − ε_c)) and Berg friction σ_r + u(σ_fmax − sσ_r)/(d_0 + su), u = ε − ε_r */
static inline double stress(const bs_law *law, const bs_layer *l, double eps, int up, double *slope)
{
    double u = eps - l->er[up], w = 1.0 / (l->d0[up] + (up ? u : -u)), q = l->num[up] * w;
    double e2 = eps * eps;
    *slope = law->two_mu * (1.0 + 3.0 * law->beta * e2) + law->b + q * l->d0[up] * w;
    return law->two_mu * eps * (1.0 + law->beta * e2) + l->z + law->b * (eps - l->eps_c)
           + l->sr[up] + u * q;
}

/* the size of the terms of stress(): its rounding error is a few ulp of this, whatever the
 * residual's own size (a stress target far below the memory's or the friction's stress) */
static inline double stress_size(const bs_law *law, const bs_layer *l, double eps, int up)
{
    double u = eps - l->er[up], w = 1.0 / (l->d0[up] + (up ? u : -u));
    return fabs(law->two_mu * eps * (1.0 + law->beta * eps * eps)) + fabs(l->z)
           + fabs(law->b * (eps - l->eps_c)) + fabs(l->sr[up]) + fabs(u * l->num[up] * w);
}

/* the layer's stress at its committed strain (both branches meet there) */
static inline double at_rest(const bs_law *law, const bs_layer *l)
{
    return law->two_mu * l->eps_c * (1.0 + law->beta * l->eps_c * l->eps_c) + l->z + l->sig_c;
}

/* Newton's correction of the layer's strain for the stress target, in one division: with
 * d = d_0 + su, (σ − target)/σ' = N d/D and 1/σ' = d²/D, N = (σ − target) d and D = σ' d².
 * Returns (σ − target)/σ'; sets l->inv = 1/σ'. */
static inline double correction(const bs_law *law, bs_layer *l, double eps, int up, double target)
{
    double u = eps - l->er[up], d = l->d0[up] + (up ? u : -u), e2 = eps * eps;
    double rest = law->two_mu * eps * (1.0 + law->beta * e2) + l->z + law->b * (eps - l->eps_c)
                  + l->sr[up] - target;
    double slope = law->two_mu * (1.0 + 3.0 * law->beta * e2) + law->b;
    double w = d / (slope * d * d + l->num[up] * l->d0[up]);
    l->inv = d * w;
    return (rest * d + u * l->num[up]) * w;
}

/* the memory's stress Σ m g_j e^{−λ_j h} z_j, in four partial sums (no chain of J dependent
 * additions) */
static inline double memory_stress(const double *gd, const double *z, int J)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int j = 0;
    for (; j + 4 <= J; j += 4) {
        s0 += gd[j] * z[j];
        s1 += gd[j + 1] * z[j + 1];
        s2 += gd[j + 2] * z[j + 2];
        s3 += gd[j + 3] * z[j + 3];
    }
    for (; j < J; j++) s0 += gd[j] * z[j];
    return (s0 + s1) + (s2 + s3);
}

/* Berg's friction stress on a branch, u = ε − ε_r along it (s: its direction) */
static inline double berg(double sr, double num, double d0, double s, double u)
{
    return sr + u * (num / (d0 + s * u));
}

/* the friction branch a layer moves on in direction s from its committed state: on along its
 * direction from its last reversal point, or reversing at the committed point; its reversal
 * point (ε_r, σ_r), σ_fmax − sσ_r and d_0 = ε½(1 − sσ_r/σ_fmax) (without friction, σ_fmax = 0,
 * the branch is flat at σ_r = 0) */
typedef struct {
    double er, sr, num, d0;
} branch_t;

static inline branch_t branch(const bs_law *law, const double *layer, double s)
{
    double smax = law->smax;
    branch_t b;
    int on = layer[BK_LAYER_DIR] == s;
    b.er = on ? layer[BK_LAYER_EPS_S] : layer[BK_LAYER_EPS];
    b.sr = on ? layer[BK_LAYER_SIG_S] : layer[BK_LAYER_SIG_F];
    b.num = smax > 0.0 ? smax - s * b.sr : 0.0;
    b.d0 = smax > 0.0 ? law->ehalf - s * b.sr * law->ehalf_smax : 1.0;
    return b;
}

/* the layer's law for this step from its committed state: the memory's stress and both
 * friction branches */
static void prepare_layer(bs_layer *l, const bs_law *law, const double *layer, const double *gd,
                          int J)
{
    l->z = memory_stress(gd, layer + BK_LAYER_HEAD, J);
    l->eps_c = layer[BK_LAYER_EPS];
    l->sig_c = layer[BK_LAYER_SIG_F];
    l->dir = layer[BK_LAYER_DIR];
    for (int up = 0; up < 2; up++) {
        branch_t b = branch(law, layer, up ? 1.0 : -1.0);
        l->er[up] = b.er;
        l->sr[up] = b.sr;
        l->num[up] = b.num;
        l->d0[up] = b.d0;
    }
}

/* the exponentials' states after the step, e^{−λ_j h}(z_j + Δε), into `out` (`z` itself, or
 * a buffer apart); in pairs, each pair read before it is written (the compiler's vector
 * instructions at -O2) */
static void decay_memory(double *out, const double *z, const double *decay, double step, int J)
{
    int j = 0;
    for (; j + 2 <= J; j += 2) {
        double a = decay[j] * (z[j] + step), b = decay[j + 1] * (z[j + 1] + step);
        out[j] = a;
        out[j + 1] = b;
    }
    if (j < J) out[j] = decay[j] * (z[j] + step);
}

/* the layer's state after the step, ending at strain eps */
static void commit_layer(const bs_layer *l, const double *layer, double *out, double eps,
                         const double *decay, int J)
{
    double step = eps - l->eps_c;
    decay_memory(out + BK_LAYER_HEAD, layer + BK_LAYER_HEAD, decay, step, J);
    out[BK_LAYER_STEP] = step;
    if (step == 0.0) {
        if (out != layer) memcpy(out, layer, BK_LAYER_STEP * sizeof(double));
        return;
    }
    int up = step > 0.0;
    double u = eps - l->er[up];
    out[BK_LAYER_EPS_S] = l->er[up];
    out[BK_LAYER_SIG_S] = l->sr[up];
    out[BK_LAYER_DIR] = up ? 1.0 : -1.0;
    out[BK_LAYER_SIG_F] = berg(l->sr[up], l->num[up], l->d0[up], up ? 1.0 : -1.0, u);
    out[BK_LAYER_EPS] = eps;
}

void bs_prepare(bs_layer *L, int n, const bs_law *law, const double *layer, size_t layer_size,
                const double *pc, const double *gd, int J)
{
    for (int k = 0; k < n; k++, pc += 4) {
        prepare_layer(&L[k], law, layer + k * layer_size, gd, J);
        L[k].p = pc[0];
        L[k].ip = pc[1];
        L[k].c = pc[2];
        L[k].ic = pc[3];
    }
}

void bs_commit(const bs_layer *L, int n, const double *layer, double *out, size_t layer_size,
               const double *decay, int J)
{
    for (int k = 0; k < n; k++)
        commit_layer(&L[k], layer + k * layer_size, out + k * layer_size, L[k].eps, decay, J);
}

/* ------------------------------------------------------------------------------------------ */
/* the series equations of a channel: σ_k(ε_k) = p_k F (p_k = 2c_k/S_k), Σ ε_k/c_k + C_b F = x */

/* The one Newton over the N + 1 unknowns (ε_k, F), O(N) an iteration by the arrow-shaped
 * Jacobian: δε_k = (p_k δF − r_k)/σ'_k and δF from the compatibility row (the equations are
 * linear in F: the first iterate needs strains only). It starts from the strains the last step's
 * changes extrapolate to, by `ratio` = this step's change of the drive over the last one (0: at
 * the committed strains, on the branches the layers last moved along: the last step's tangent).
 * Each iterate's branch is the side of ε_c it is on; a step across ε_c (friction's kink) stops
 * there. It ends when its relative step is below NEWTON_TOLERANCE, or when the step before
 * the last was already small and the last one shows quadratic convergence (s_i (s_i/s_{i−1})²,
 * the next step's size, below NEWTON_TOLERANCE / 100). 0 when converged; 1 when it does not
 * reduce its residual or runs out of iterations: the caller falls back to the nested solve. */
int bs_newton(const bs_law *law, bs_layer *L, const double *layer, size_t layer_size, int n,
              double cb, double x, double ratio, double scale, double *load, long *count)
{
    double F = *load, previous = INFINITY, last = INFINITY;
    for (int k = 0; k < n; k++) {
        bs_layer *l = &L[k];
        l->eps = l->eps_c + ratio * layer[k * layer_size + BK_LAYER_STEP];
        l->up = l->eps != l->eps_c ? l->eps > l->eps_c : l->dir >= 0.0;
    }
    for (int it = 0; it < NEWTON_ITERATIONS; it++) {
        double g = cb * F - x, dg = cb, rg = 0.0, merit = 0.0;
        int bad = 0;  /* a slope not positive (NaN included): checked once for all layers */
        for (int k = 0; k < n; k++) {
            bs_layer *l = &L[k];
            if (l->eps != l->eps_c) {
                l->up = l->eps > l->eps_c;
            } else if (it > 0) {  /* at the kink: the side the load pushes it to */
                double t = l->p * F - at_rest(law, l);
                if (t != 0.0) l->up = t > 0.0;
            }
            double ri = correction(law, l, l->eps, l->up, l->p * F);
            bad |= !(l->inv > 0.0);
            l->r = ri;
            g += l->eps * l->ic;
            dg += l->p * l->ic * l->inv;
            rg += ri * l->ic;
            merit += fabs(ri) * l->ic;
        }
        if (count) *count += n;
        merit += fabs(g);
        if (bad || !isfinite(merit) || (it >= 4 && !(merit < previous))) return 1;
        previous = merit;
        double dF = (rg - g) / dg;
        F += dF;
        if (!isfinite(F)) return 1;
        /* the relative step: the largest of |δF|/scale and |δε_k|/room_k, as top/bottom */
        double top = it ? fabs(dF) : 0.0, bottom = bs_larger(fabs(F), scale);  /* F₀: no guess */
        int kinked = 0;
        for (int k = 0; k < n; k++) {
            bs_layer *l = &L[k];
            double de = l->p * dF * l->inv - l->r, eps = l->eps + de;
            if (l->up ? eps < l->eps_c : eps > l->eps_c) {
                eps = l->eps_c;
                kinked = 1;
            }
            double e = fabs(de), room = fabs(eps) + fabs(l->eps_c);
            if (e * bottom > top * room || (top == 0.0 && bottom == 0.0)) top = e, bottom = room;
            l->eps = eps;
        }
        double size = bottom > 0.0 ? top / bottom : top > 0.0 ? INFINITY : 0.0;
        if (!kinked && (size <= NEWTON_TOLERANCE
                        || (last < 1e-3 && size * (size / last) * (size / last)
                                               <= 0.01 * NEWTON_TOLERANCE))) {
            *load = F;
            return 0;
        }
        last = kinked ? INFINITY : size;
    }
    return 1;
}

/* a Newton step kept inside the bracket (lo, hi): bisection where it leaves it; away from the
 * finite bound where the other is not known yet */
static double bracketed(double x, double step, double lo, double hi)
{
    double next = x + step;
    if (next > lo && next < hi) return next;
    if (isinf(lo)) return hi - 2.0 * fabs(step);
    if (isinf(hi)) return lo + 2.0 * fabs(step);
    return 0.5 * (lo + hi);
}

/* nested solve, inner: the strain at which the layer carries the stress `target` (safeguarded
 * Newton from the layer's last iterate); l->eps, l->inv = 1/σ' there */
static int layer_strain(const bs_law *law, bs_layer *l, double target, long *count)
{
    double eps_c = l->eps_c, slope, eps;
    double at_c = at_rest(law, l);
    int up = target > at_c;
    if (target == at_c) {
        l->eps = eps_c;
        stress(law, l, eps_c, l->dir >= 0.0, &slope);
        l->inv = 1.0 / slope;
        return 0;
    }
    double lo = up ? eps_c : -INFINITY, hi = up ? INFINITY : eps_c;
    if (l->eps > lo && l->eps < hi) {
        eps = l->eps;
    } else {
        stress(law, l, eps_c, up, &slope);
        eps = eps_c + (target - at_c) / slope;
    }
    for (int i = 0; i < MAX_ITERATIONS; i++) {
        double r = stress(law, l, eps, up, &slope) - target;
        if (count) (*count)++;
        if (!isfinite(r) || !(slope > 0.0)) return 1;
        if (r == 0.0) break;
        if (r < 0.0) lo = eps; else hi = eps;
        double step = -r / slope;
        double tol = LAYER_TOLERANCE * bs_larger(fabs(eps), fabs(eps - eps_c));
        /* a residual within its own rounding (terms far larger than the target's: a tiny
         * strain after a long step) moves the strain by no more than that rounding's share */
        if (fabs(r) <= ROUNDING * (stress_size(law, l, eps, up) + fabs(target))) tol = bs_larger(tol, fabs(step));
        if (fabs(step) <= tol) {
            eps += step;
            break;
        }
        double next = bracketed(eps, step, lo, hi);
        if (hi - lo <= tol) {
            eps = next;
            break;
        }
        eps = next;
        if (i == MAX_ITERATIONS - 1) return 1;
    }
    if (up ? eps < eps_c : eps > eps_c) eps = eps_c;  /* never across the reversal */
    stress(law, l, eps, up, &slope);
    l->eps = eps;
    l->inv = 1.0 / slope;
    return 0;
}

/* The nested solve (the fallback: slower, robust): g(F) = Σ ε_k(F)/c_k + C_b F − x increases
 * strictly; Newton on F safeguarded by bisection, each ε_k(F) by layer_strain. 0 when converged;
 * 1 with a sentence in text. */
int bs_nested(const bs_law *law, bs_layer *L, int n, double cb, double x, double scale,
              double *load, long *count, char *text, size_t length)
{
    double lo = -INFINITY, hi = INFINITY, F = *load;
    for (int k = 0; k < n; k++) L[k].eps = L[k].eps_c;
    for (int i = 0; i < MAX_ITERATIONS; i++) {
        double g = cb * F - x, dg = cb;
        for (int k = 0; k < n; k++) {
            if (layer_strain(law, &L[k], L[k].p * F, count)) {
                snprintf(text, length, "layer %d: the layer's strain did not converge at load %g",
                         k + 1, F);
                return 1;
            }
            g += L[k].eps * L[k].ic;
            dg += L[k].p * L[k].ic * L[k].inv;
        }
        if (g == 0.0) break;
        if (g < 0.0) lo = F; else hi = F;
        double step = -g / dg, guess = bracketed(F, step, lo, hi);
        double tol = LOAD_TOLERANCE * bs_larger(fabs(F), scale);
        if (fabs(step) <= tol || hi - lo <= tol) break;
        if (i == MAX_ITERATIONS - 1 || !isfinite(guess)) {
            snprintf(text, length, "the series equations did not converge in %d iterations",
                     MAX_ITERATIONS);
            return 1;
        }
        F = guess;
    }
    *load = F;
    return 0;
}

/* a layer alone with the drive (no bulk spring): its strain c·x is known, its load σ S/(2c)
 * follows in one evaluation, in registers; its state after the step into `out` */
double bs_direct(const bs_law *law, const double *layer, double *out, double x, const double *pc,
                 const double *gd, const double *decay, int J)
{
    double eps = x * pc[2], eps_c = layer[BK_LAYER_EPS], step = eps - eps_c;
    double s = step > 0.0 ? 1.0 : -1.0, e2 = eps * eps;
    branch_t b = branch(law, layer, s);
    double fr = berg(b.sr, b.num, b.d0, s, eps - b.er);
    double sigma = law->two_mu * eps * (1.0 + law->beta * e2)
                   + memory_stress(gd, layer + BK_LAYER_HEAD, J) + law->b * step + fr;
    decay_memory(out + BK_LAYER_HEAD, layer + BK_LAYER_HEAD, decay, step, J);
    out[BK_LAYER_STEP] = step;
    if (step == 0.0) {
        if (out != layer) memcpy(out, layer, BK_LAYER_STEP * sizeof(double));
    } else {
        out[BK_LAYER_EPS_S] = b.er;
        out[BK_LAYER_SIG_S] = b.sr;
        out[BK_LAYER_DIR] = s;
        out[BK_LAYER_SIG_F] = fr;
        out[BK_LAYER_EPS] = eps;
    }
    return sigma * pc[1];
}
