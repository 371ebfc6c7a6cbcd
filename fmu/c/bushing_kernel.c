/* The bushing as a time-domain element: the generic kernel. See bushing_kernel.h and
 * docs/element.md (the model, the held-input step, the series equations). */
#include "bushing_kernel.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MAX_ITERATIONS 200
#define NEWTON_ITERATIONS 40   /* the one-level Newton's; beyond, the nested solve */
#define NEWTON_TOLERANCE 1e-13 /* its relative steps in the load and the strains */
#define GUESS_RATIO 2.0        /* the last step's changes guess the next within this ratio */
#define LAYER_TOLERANCE 2e-15  /* nested solve: relative step in a layer's strain, a few ulp */
#define LOAD_TOLERANCE 1e-14   /* nested solve: relative step in the channel's load */

/* ------------------------------------------------------------------------------------------ */
/* layout */

size_t bk_channel_parameters(const bk_sizes *sizes, int channel)
{
    size_t at = BK_SCALARS + 2 * (size_t)sizes->exponentials;
    for (int c = 0; c < channel; c++) at += 2 * (size_t)sizes->layers[c] + 1;
    return at;
}

size_t bk_parameter_count(const bk_sizes *sizes)
{
    return bk_channel_parameters(sizes, BK_CHANNELS);
}

size_t bk_channel_state(const bk_sizes *sizes, int channel)
{
    size_t at = 0, layer = BK_LAYER_HEAD + (size_t)sizes->exponentials;
    for (int c = 0; c < channel; c++) at += BK_CHANNEL_HEAD + layer * (size_t)sizes->layers[c];
    return at;
}

size_t bk_state_count(const bk_sizes *sizes)
{
    return bk_channel_state(sizes, BK_CHANNELS);
}

/* one layer during a step: its law (the friction branches either side of the committed strain,
 * [0] moving down, [1] moving up) and the series solve's iterate. Scratch, in the work buffer. */
typedef struct {
    double eps_c, sig_c, dir;  /* committed strain, friction stress, direction (−1, 0, +1) */
    double z;                  /* Σ m g_j e^{−λ_j h} z_j: the memory's stress */
    double p, ip, c, ic;       /* p = 2c/S, 1/p, c and 1/c */
    double er[2], sr[2], num[2], d0[2];  /* each branch's reversal point, σ_fmax − sσ_r, d_0 */
    double eps, r, inv;        /* the iterate, its correction (σ − pF)/σ', 1/σ' there */
    int up;                    /* the iterate's branch */
} layer_t;
#define LAYER_DOUBLES ((sizeof(layer_t) + sizeof(double) - 1) / sizeof(double))

/* work: [h of the cache, B of the cache, e^{−λ_j h} (J), m g_j e^{−λ_j h} (J), each channel's
 * elastic stiffness, per layer of every channel 2c/S, S/(2c), c and 1/c, then a layer_t per
 * layer of the widest channel] */
enum { WORK_H, WORK_B, WORK_HEAD };

static size_t all_layers(const bk_sizes *sizes)
{
    size_t n = 0;
    for (int c = 0; c < BK_CHANNELS; c++) n += (size_t)sizes->layers[c];
    return n;
}

size_t bk_work_count(const bk_sizes *sizes)
{
    int widest = 0;
    for (int c = 0; c < BK_CHANNELS; c++)
        if (sizes->layers[c] > widest) widest = sizes->layers[c];
    return WORK_HEAD + 2 * (size_t)sizes->exponentials + BK_CHANNELS + 4 * all_layers(sizes)
           + LAYER_DOUBLES * (size_t)widest;
}

void bk_work_reset(const bk_sizes *sizes, double *work)
{
    memset(work, 0, bk_work_count(sizes) * sizeof(double));
    work[WORK_H] = -1.0;  /* no step cached */
}

static const char *SCALAR_NAMES[BK_SCALARS] = {"mu", "m", "alpha", "sigma_f_max", "eps_half",
                                               "beta", "viscosity"};
static const char *CHANNEL_NAMES[BK_CHANNELS] = {"dx", "dy", "dz", "rx", "ry", "rz"};

void bk_parameter_name(const bk_sizes *sizes, size_t index, char *name, size_t length)
{
    size_t J = (size_t)sizes->exponentials;
    if (index < BK_SCALARS) {
        snprintf(name, length, "%s", SCALAR_NAMES[index]);
        return;
    }
    if (index < BK_SCALARS + 2 * J) {
        size_t j = index - BK_SCALARS;
        snprintf(name, length, "%s[%zu]", j < J ? "rate" : "weight", j % J + 1);
        return;
    }
    for (int c = 0; c < BK_CHANNELS; c++) {
        size_t start = bk_channel_parameters(sizes, c), n = (size_t)sizes->layers[c];
        if (index < start + 2 * n + 1) {
            size_t k = index - start;
            if (k == 2 * n)
                snprintf(name, length, "%s.compliance", CHANNEL_NAMES[c]);
            else
                snprintf(name, length, "%s.%s[%zu]", CHANNEL_NAMES[c], k < n ? "S" : "c",
                         k % n + 1);
            return;
        }
    }
    snprintf(name, length, "?");
}

/* ------------------------------------------------------------------------------------------ */
/* checks */

static int fail(char *message, size_t length, const char *text)
{
    if (message && length) snprintf(message, length, "%s", text);
    return 1;
}

int bk_check_sizes(const bk_sizes *sizes, char *message, size_t length)
{
    char text[BK_MESSAGE];
    if (sizes->exponentials < 0 || sizes->exponentials > BK_MAX_EXPONENTIALS) {
        snprintf(text, sizeof text, "exponentials: %d, allowed 0 to %d", sizes->exponentials,
                 BK_MAX_EXPONENTIALS);
        return fail(message, length, text);
    }
    for (int c = 0; c < BK_CHANNELS; c++) {
        if (sizes->layers[c] < 1 || sizes->layers[c] > BK_MAX_LAYERS) {
            snprintf(text, sizeof text, "channel %d: %d layers, allowed 1 to %d", c,
                     sizes->layers[c], BK_MAX_LAYERS);
            return fail(message, length, text);
        }
    }
    return 0;
}

static int bad_value(char *message, size_t length, const char *name, long index, double value,
                     const char *rule)
{
    char text[BK_MESSAGE];
    if (index >= 0)
        snprintf(text, sizeof text, "%s[%ld] = %g: must be %s", name, index + 1, value, rule);
    else
        snprintf(text, sizeof text, "%s = %g: must be %s", name, value, rule);
    return fail(message, length, text);
}

int bk_check_parameters(const bk_sizes *sizes, const double *p, char *message, size_t length)
{
    int J = sizes->exponentials;
    if (bk_check_sizes(sizes, message, length)) return 1;
    for (int i = 0; i < BK_SCALARS; i++) {
        if (!isfinite(p[i]) || p[i] < 0.0)
            return bad_value(message, length, SCALAR_NAMES[i], -1, p[i], "a finite number ≥ 0");
    }
    if (!(p[BK_MU] > 0.0)) return bad_value(message, length, "mu", -1, p[BK_MU], "positive");
    if (p[BK_ALPHA] > 1.0)
        return bad_value(message, length, "alpha", -1, p[BK_ALPHA], "between 0 and 1");
    if (p[BK_SIGMA_F_MAX] > 0.0 && !(p[BK_EPS_HALF] > 0.0))
        return bad_value(message, length, "eps_half", -1, p[BK_EPS_HALF],
                         "positive where sigma_f_max is");
    for (int j = 0; j < J; j++) {
        double rate = p[BK_SCALARS + j], weight = p[BK_SCALARS + J + j];
        if (!isfinite(rate) || !(rate > 0.0))
            return bad_value(message, length, "rate", j, rate, "a positive finite number");
        if (!isfinite(weight) || weight < 0.0)
            return bad_value(message, length, "weight", j, weight, "a finite number ≥ 0");
    }
    for (int c = 0; c < BK_CHANNELS; c++) {
        const double *q = p + bk_channel_parameters(sizes, c);
        int n = sizes->layers[c];
        char name[32];
        for (int k = 0; k < 2 * n; k++) {
            if (!isfinite(q[k]) || !(q[k] > 0.0)) {
                snprintf(name, sizeof name, "%s.%s", CHANNEL_NAMES[c], k < n ? "S" : "c");
                return bad_value(message, length, name, k % n, q[k], "a positive finite number");
            }
        }
        if (!isfinite(q[2 * n]) || q[2 * n] < 0.0) {
            snprintf(name, sizeof name, "%s.compliance", CHANNEL_NAMES[c]);
            return bad_value(message, length, name, -1, q[2 * n], "a finite number ≥ 0");
        }
    }
    return 0;
}

/* one layer's law over a step */

typedef struct {
    double two_mu, beta, b;  /* 2µ, β, B = m Σ g_j e^{−λ_j h} + c_v / h */
} law_t;

/* the layer's stress σ(ε) and slope dσ/dε on branch `up`: elastic, memory (its stress at ε_c plus
 * B(ε − ε_c)) and Berg friction σ_r + u(σ_fmax − sσ_r)/(d_0 + su), u = ε − ε_r */
static inline double stress(const law_t *law, const layer_t *l, double eps, int up, double *slope)
{
    double u = eps - l->er[up], w = 1.0 / (l->d0[up] + (up ? u : -u)), q = l->num[up] * w;
    double e2 = eps * eps;
    *slope = law->two_mu * (1.0 + 3.0 * law->beta * e2) + law->b + q * l->d0[up] * w;
    return law->two_mu * eps * (1.0 + law->beta * e2) + l->z + law->b * (eps - l->eps_c)
           + l->sr[up] + u * q;
}

/* the layer's stress at its committed strain (both branches meet there) */
static inline double at_rest(const law_t *law, const layer_t *l)
{
    return law->two_mu * l->eps_c * (1.0 + law->beta * l->eps_c * l->eps_c) + l->z + l->sig_c;
}

/* Newton's correction of the layer's strain for the stress target, in one division: with
 * d = d_0 + su, (σ − target)/σ' = N d/D and 1/σ' = d²/D, N = (σ − target) d and D = σ' d².
 * Returns (σ − target)/σ'; sets l->inv = 1/σ'. */
static inline double correction(const law_t *law, layer_t *l, double eps, int up, double target)
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

static inline branch_t branch(const double *layer, double s, double smax, double ehalf_smax,
                              double ehalf)
{
    branch_t b;
    int on = layer[BK_LAYER_DIR] == s;
    b.er = on ? layer[BK_LAYER_EPS_S] : layer[BK_LAYER_EPS];
    b.sr = on ? layer[BK_LAYER_SIG_S] : layer[BK_LAYER_SIG_F];
    b.num = smax > 0.0 ? smax - s * b.sr : 0.0;
    b.d0 = smax > 0.0 ? ehalf - s * b.sr * ehalf_smax : 1.0;
    return b;
}

/* the layer's law for this step from its committed state: the memory's stress and both
 * friction branches */
static void prepare_layer(layer_t *l, const double *layer, const double *gd, int J, double smax,
                          double ehalf_smax, double ehalf)
{
    l->z = memory_stress(gd, layer + BK_LAYER_HEAD, J);
    l->eps_c = layer[BK_LAYER_EPS];
    l->sig_c = layer[BK_LAYER_SIG_F];
    l->dir = layer[BK_LAYER_DIR];
    for (int up = 0; up < 2; up++) {
        branch_t b = branch(layer, up ? 1.0 : -1.0, smax, ehalf_smax, ehalf);
        l->er[up] = b.er;
        l->sr[up] = b.sr;
        l->num[up] = b.num;
        l->d0[up] = b.d0;
    }
}

/* the exponentials' states after the step, in place or into another buffer (no overlap); in
 * pairs (the compiler's vector instructions at -O2) */
static void decay_in_place(double *restrict z, const double *restrict decay, double step, int J)
{
    int j = 0;
    for (; j + 2 <= J; j += 2) {
        double a = decay[j] * (z[j] + step), b = decay[j + 1] * (z[j + 1] + step);
        z[j] = a;
        z[j + 1] = b;
    }
    if (j < J) z[j] = decay[j] * (z[j] + step);
}

static void decay_into(double *restrict out, const double *restrict z,
                       const double *restrict decay, double step, int J)
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
static void commit_layer(const layer_t *l, const double *layer, double *out, double eps,
                         const double *decay, int J)
{
    double step = eps - l->eps_c;
    if (out == layer)
        decay_in_place(out + BK_LAYER_HEAD, decay, step, J);
    else
        decay_into(out + BK_LAYER_HEAD, layer + BK_LAYER_HEAD, decay, step, J);
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

/* ------------------------------------------------------------------------------------------ */
/* the series equations of a channel: σ_k(ε_k) = p_k F (p_k = 2c_k/S_k), Σ ε_k/c_k + C_b F = x */

static inline double larger(double a, double b) { return a > b ? a : b; }

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
static int series_newton(const law_t *law, layer_t *L, const double *layer, size_t layer_size,
                         int n, double cb, double x, double ratio, double scale, double *load,
                         long *count)
{
    double F = *load, previous = INFINITY, last = INFINITY;
    for (int k = 0; k < n; k++) {
        layer_t *l = &L[k];
        l->eps = l->eps_c + ratio * layer[k * layer_size + BK_LAYER_STEP];
        l->up = l->eps != l->eps_c ? l->eps > l->eps_c : l->dir >= 0.0;
    }
    for (int it = 0; it < NEWTON_ITERATIONS; it++) {
        double g = cb * F - x, dg = cb, rg = 0.0, merit = 0.0;
        for (int k = 0; k < n; k++) {
            layer_t *l = &L[k];
            if (l->eps != l->eps_c) {
                l->up = l->eps > l->eps_c;
            } else if (it > 0) {  /* at the kink: the side the load pushes it to */
                double t = l->p * F - at_rest(law, l);
                if (t != 0.0) l->up = t > 0.0;
            }
            double ri = correction(law, l, l->eps, l->up, l->p * F);
            if (!isfinite(ri) || !(l->inv > 0.0)) return 1;
            l->r = ri;
            g += l->eps * l->ic;
            dg += l->p * l->ic * l->inv;
            rg += ri * l->ic;
            merit += fabs(ri) * l->ic;
        }
        if (count) *count += n;
        merit += fabs(g);
        if (it >= 4 && !(merit < previous)) return 1;
        previous = merit;
        double dF = (rg - g) / dg;
        F += dF;
        if (!isfinite(F)) return 1;
        /* the relative step: the largest of |δF|/scale and |δε_k|/room_k, as top/bottom */
        double top = it ? fabs(dF) : 0.0, bottom = larger(fabs(F), scale);  /* F₀: no guess */
        int kinked = 0;
        for (int k = 0; k < n; k++) {
            layer_t *l = &L[k];
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
static int layer_strain(const law_t *law, layer_t *l, double target, long *count)
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
        double tol = LAYER_TOLERANCE * larger(fabs(eps), fabs(eps - eps_c));
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
static int series_nested(const law_t *law, layer_t *L, int n, double cb, double x, double scale,
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
        double tol = LOAD_TOLERANCE * larger(fabs(F), scale);
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
static double direct_layer(const law_t *law, const double *layer, double *out, double x,
                           const double *pc, const double *gd, const double *decay, int J,
                           double smax, double ehalf_smax, double ehalf)
{
    double eps = x * pc[2], eps_c = layer[BK_LAYER_EPS], step = eps - eps_c;
    double s = step > 0.0 ? 1.0 : -1.0, e2 = eps * eps;
    branch_t b = branch(layer, s, smax, ehalf_smax, ehalf);
    double fr = berg(b.sr, b.num, b.d0, s, eps - b.er);
    double sigma = law->two_mu * eps * (1.0 + law->beta * e2)
                   + memory_stress(gd, layer + BK_LAYER_HEAD, J) + law->b * step + fr;
    if (out == layer)
        decay_in_place(out + BK_LAYER_HEAD, decay, step, J);
    else
        decay_into(out + BK_LAYER_HEAD, layer + BK_LAYER_HEAD, decay, step, J);
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

/* ------------------------------------------------------------------------------------------ */
/* a step */

int bk_advance(const bk_sizes *sizes, const double *p, const double *state, double *next,
               const double x[BK_CHANNELS], double h, double f[BK_CHANNELS], double *work,
               long *evaluations, char *message, size_t length)
{
    char text[BK_MESSAGE], why[BK_MESSAGE / 2];
    int J = sizes->exponentials;
    size_t layer_size = BK_LAYER_HEAD + (size_t)J;
    if (!isfinite(h) || !(h > 0.0)) {
        snprintf(text, sizeof text, "step size %g s: must be a positive finite number", h);
        return fail(message, length, text);
    }
    for (int c = 0; c < BK_CHANNELS; c++) {
        if (!isfinite(x[c])) {
            snprintf(text, sizeof text, "input %s = %g: must be a finite number", CHANNEL_NAMES[c],
                     x[c]);
            return fail(message, length, text);
        }
    }
    double *decay = work + WORK_HEAD, *gd = decay + J, *stiff = gd + J, *pc = stiff + BK_CHANNELS;
    layer_t *L = (layer_t *)(pc + 4 * all_layers(sizes));
    if (work[WORK_H] != h) {  /* once per step size (and after bk_work_reset) */
        double b = 0.0;
        for (int j = 0; j < J; j++) {
            decay[j] = exp(-p[BK_SCALARS + j] * h);
            gd[j] = p[BK_M] * p[BK_SCALARS + J + j] * decay[j];
            b += gd[j];
        }
        work[WORK_B] = b + p[BK_VISCOSITY] / h;
        work[WORK_H] = h;
        double *at = pc;
        for (int c = 0; c < BK_CHANNELS; c++) {
            int n = sizes->layers[c];
            const double *S = p + bk_channel_parameters(sizes, c), *cf = S + n;
            double soft = 0.0;  /* the channel's elastic compliance, for the load's scale */
            for (int k = 0; k < n; k++, at += 4) {
                at[0] = 2.0 * cf[k] / S[k];
                at[1] = S[k] / (2.0 * cf[k]);
                at[2] = cf[k];
                at[3] = 1.0 / cf[k];
                soft += at[0] * at[3];
            }
            stiff[c] = 1.0 / (cf[n] + soft / (2.0 * p[BK_MU] + work[WORK_B]));
        }
    }
    law_t law = {2.0 * p[BK_MU], p[BK_BETA], work[WORK_B]};
    double smax = p[BK_SIGMA_F_MAX], ehalf = p[BK_EPS_HALF];
    double ehalf_smax = smax > 0.0 ? ehalf / smax : 0.0;
    size_t at_p = bk_channel_parameters(sizes, 0), at_s = 0;  /* the channel's offsets */
    for (int c = 0; c < BK_CHANNELS; c++) {
        int n = sizes->layers[c];
        double compliance = p[at_p + 2 * (size_t)n];
        const double *ch = state + at_s;
        double *out = next + at_s;
        at_p += 2 * (size_t)n + 1;
        at_s += BK_CHANNEL_HEAD + (size_t)n * layer_size;
        double load = ch[BK_CHANNEL_F];
        if (n == 1 && compliance == 0.0) {
            /* one layer, no bulk spring: its strain is the drive's, the load follows */
            f[c] = direct_layer(&law, ch + BK_CHANNEL_HEAD, out + BK_CHANNEL_HEAD, x[c], pc, gd,
                                decay, J, smax, ehalf_smax, ehalf);
            if (evaluations) (*evaluations)++;
            if (!isfinite(f[c])) {
                snprintf(text, sizeof text, "channel %s: the force is not finite (drive %g)",
                         CHANNEL_NAMES[c], x[c]);
                return fail(message, length, text);
            }
            out[BK_CHANNEL_STEP] = x[c] - ch[BK_CHANNEL_X];
            out[BK_CHANNEL_X] = x[c];
            out[BK_CHANNEL_F] = f[c];
            pc += 4;
            continue;
        }
        for (int k = 0; k < n; k++) {
            prepare_layer(&L[k], ch + BK_CHANNEL_HEAD + k * layer_size, gd, J, smax, ehalf_smax,
                          ehalf);
            L[k].p = pc[0];
            L[k].ip = pc[1];
            L[k].c = pc[2];
            L[k].ic = pc[3];
            pc += 4;
        }
        double scale = larger(fabs(load), (fabs(x[c]) + fabs(ch[BK_CHANNEL_X])) * stiff[c]);
        double change = x[c] - ch[BK_CHANNEL_X], ratio = change / ch[BK_CHANNEL_STEP];
        if (!(fabs(ratio) <= GUESS_RATIO)) ratio = 0.0;  /* also 0/0: held, or from rest */
#ifndef BK_SERIES_NESTED_ONLY
        if (series_newton(&law, L, ch + BK_CHANNEL_HEAD, layer_size, n, compliance, x[c],
                          ratio, scale, &load, evaluations))
#endif
        {
            load = ch[BK_CHANNEL_F];
            if (series_nested(&law, L, n, compliance, x[c], scale, &load, evaluations, why,
                              sizeof why)) {
                snprintf(text, sizeof text, "channel %s: %s (drive %g)", CHANNEL_NAMES[c],
                         why, x[c]);
                return fail(message, length, text);
            }
        }
        if (!isfinite(load)) {
            snprintf(text, sizeof text, "channel %s: the force is not finite (drive %g)",
                     CHANNEL_NAMES[c], x[c]);
            return fail(message, length, text);
        }
        for (int k = 0; k < n; k++) {
            const double *layer = ch + BK_CHANNEL_HEAD + k * layer_size;
            commit_layer(&L[k], layer, out + BK_CHANNEL_HEAD + k * layer_size, L[k].eps, decay, J);
        }
        out[BK_CHANNEL_STEP] = x[c] - ch[BK_CHANNEL_X];
        out[BK_CHANNEL_X] = x[c];
        out[BK_CHANNEL_F] = load;
        f[c] = load;
    }
    return 0;
}
