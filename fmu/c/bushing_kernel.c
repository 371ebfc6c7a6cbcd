/* The bushing as a time-domain element: the generic kernel. See bushing_kernel.h and
 * docs/element.md (the model, the held-input step, the series equations). */
#include "bushing_kernel.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MAX_ITERATIONS 200
#define LAYER_TOLERANCE 2e-15  /* relative step in a layer's strain: a few ulp */
#define LOAD_TOLERANCE 1e-14   /* relative step in the channel's load: below the spec's 1e-13 */

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

/* work: [h of the cache, B of the cache, e^{−λ_j h} (J), then per layer of the widest
 * channel: A_k, the current strain iterate, its slope] */
enum { WORK_H, WORK_B, WORK_HEAD };

size_t bk_work_count(const bk_sizes *sizes)
{
    int widest = 0;
    for (int c = 0; c < BK_CHANNELS; c++)
        if (sizes->layers[c] > widest) widest = sizes->layers[c];
    return WORK_HEAD + (size_t)sizes->exponentials + 3 * (size_t)widest;
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

/* ------------------------------------------------------------------------------------------ */
/* one layer's law over a step */

typedef struct {
    double two_mu, beta, b;  /* 2µ, β, B = m Σ g_j e^{−λ_j h} + c_v / h */
    double smax, ehalf;      /* friction: σ_fmax (0: none), ε½ */
} law_t;

typedef struct {
    double a;                /* A_k: the fractional and viscous stress at ε = 0 */
    double eps_c, sig_c;     /* the committed strain and its friction stress */
    double eps_r, sig_r, s;  /* the friction branch: its reversal point and direction */
} branch_t;

/* the branch the layer moves on when its strain goes to the `side` of the committed strain:
 * on along its direction from its last reversal point, or reversing at the committed point */
static void set_branch(branch_t *br, const double *layer, double side)
{
    br->eps_c = layer[BK_LAYER_EPS];
    br->sig_c = layer[BK_LAYER_SIG_F];
    if (layer[BK_LAYER_DIR] == side) {
        br->eps_r = layer[BK_LAYER_EPS_S];
        br->sig_r = layer[BK_LAYER_SIG_S];
    } else {
        br->eps_r = br->eps_c;
        br->sig_r = br->sig_c;
    }
    br->s = side;
}

static double friction(const law_t *law, const branch_t *br, double eps, double *slope)
{
    if (!(law->smax > 0.0)) {
        *slope = 0.0;
        return 0.0;
    }
    double u = eps - br->eps_r, s = br->s;
    double num = law->smax - s * br->sig_r;
    double d0 = law->ehalf * (1.0 - s * br->sig_r / law->smax);
    double d = d0 + s * u;
    *slope = num * d0 / (d * d);
    return br->sig_r + u * num / d;
}

/* the layer's stress σ(ε) and slope dσ/dε on its branch */
static double stress(const law_t *law, const branch_t *br, double eps, double *slope)
{
    double fslope, e2 = eps * eps;
    double sig = law->two_mu * eps * (1.0 + law->beta * e2) + br->a + law->b * eps
                 + friction(law, br, eps, &fslope);
    *slope = law->two_mu * (1.0 + 3.0 * law->beta * e2) + law->b + fslope;
    return sig;
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

/* the strain at which the layer carries the stress `target`; its slope there */
static int solve_layer(const law_t *law, const double *layer, double a, double target,
                       double guess, double *eps_out, double *slope_out, long *count)
{
    branch_t br;
    br.a = a;
    double eps_c = layer[BK_LAYER_EPS];
    double at_rest = law->two_mu * eps_c * (1.0 + law->beta * eps_c * eps_c) + a + law->b * eps_c
                     + layer[BK_LAYER_SIG_F];
    double side = target > at_rest ? 1.0 : -1.0;
    set_branch(&br, layer, side);
    double slope, eps;
    if (target == at_rest) {
        stress(law, &br, eps_c, &slope);
        *eps_out = eps_c;
        *slope_out = slope;
        return 0;
    }
    double lo = side > 0 ? eps_c : -INFINITY, hi = side > 0 ? INFINITY : eps_c;
    if (guess > lo && guess < hi) {
        eps = guess;
    } else {
        stress(law, &br, eps_c, &slope);
        eps = eps_c + (target - at_rest) / slope;
    }
    for (int i = 0; i < MAX_ITERATIONS; i++) {
        double r = stress(law, &br, eps, &slope) - target;
        if (count) (*count)++;
        if (!isfinite(r) || !(slope > 0.0)) return 1;
        if (r == 0.0) break;
        if (r < 0.0) lo = eps; else hi = eps;
        double step = -r / slope;
        double tol = LAYER_TOLERANCE * fmax(fabs(eps), fabs(eps - eps_c));
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
    if (side > 0 ? eps < eps_c : eps > eps_c) eps = eps_c;  /* never across the reversal */
    stress(law, &br, eps, &slope);
    *eps_out = eps;
    *slope_out = slope;
    return 0;
}

/* the layer's state after the step, ending at strain eps */
static void commit_layer(const law_t *law, const double *layer, double *out, double eps,
                         const double *decay, int J)
{
    double eps_c = layer[BK_LAYER_EPS];
    for (int j = 0; j < J; j++)
        out[BK_LAYER_HEAD + j] = decay[j] * (layer[BK_LAYER_HEAD + j] + eps - eps_c);
    if (eps == eps_c) {
        if (out != layer) memcpy(out, layer, BK_LAYER_HEAD * sizeof(double));
        return;
    }
    double side = eps > eps_c ? 1.0 : -1.0, slope;
    branch_t br;
    br.a = 0.0;
    set_branch(&br, layer, side);
    double sig_f = friction(law, &br, eps, &slope);
    out[BK_LAYER_EPS_S] = br.eps_r;
    out[BK_LAYER_SIG_S] = br.sig_r;
    out[BK_LAYER_DIR] = side;
    out[BK_LAYER_SIG_F] = sig_f;
    out[BK_LAYER_EPS] = eps;
}

/* ------------------------------------------------------------------------------------------ */
/* a step */

int bk_advance(const bk_sizes *sizes, const double *p, const double *state, double *next,
               const double x[BK_CHANNELS], double h, double f[BK_CHANNELS], double *work,
               long *evaluations, char *message, size_t length)
{
    char text[BK_MESSAGE];
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
    double *decay = work + WORK_HEAD;
    if (work[WORK_H] != h) {  /* e^{−λ_j h} and B, once per step size */
        double b = 0.0;
        for (int j = 0; j < J; j++) {
            decay[j] = exp(-p[BK_SCALARS + j] * h);
            b += p[BK_SCALARS + J + j] * decay[j];
        }
        work[WORK_B] = p[BK_M] * b + p[BK_VISCOSITY] / h;
        work[WORK_H] = h;
    }
    law_t law = {2.0 * p[BK_MU], p[BK_BETA], work[WORK_B], p[BK_SIGMA_F_MAX], p[BK_EPS_HALF]};
    const double *weight = p + BK_SCALARS + J;
    for (int c = 0; c < BK_CHANNELS; c++) {
        int n = sizes->layers[c];
        const double *S = p + bk_channel_parameters(sizes, c), *cf = S + n;
        double compliance = cf[n];
        const double *ch = state + bk_channel_state(sizes, c);
        double *out = next + bk_channel_state(sizes, c);
        double *A = decay + J, *eps = A + n, *slope = eps + n;
        double load;
        for (int k = 0; k < n; k++) {
            const double *layer = ch + BK_CHANNEL_HEAD + k * layer_size;
            double e_n = layer[BK_LAYER_EPS], frac = 0.0;
            for (int j = 0; j < J; j++) frac += weight[j] * decay[j] * (layer[BK_LAYER_HEAD + j] - e_n);
            A[k] = p[BK_M] * frac - p[BK_VISCOSITY] * e_n / h;
            eps[k] = e_n;
        }
        if (n == 1 && compliance == 0.0) {
            /* one layer, no bulk spring: its strain is the drive's, the load follows */
            const double *layer = ch + BK_CHANNEL_HEAD;
            branch_t br;
            br.a = A[0];
            eps[0] = cf[0] * x[c];
            set_branch(&br, layer, eps[0] > layer[BK_LAYER_EPS] ? 1.0 : -1.0);
            if (eps[0] == layer[BK_LAYER_EPS]) br.eps_r = br.eps_c, br.sig_r = br.sig_c;
            load = stress(&law, &br, eps[0], &slope[0]) * S[0] / (2.0 * cf[0]);
            if (evaluations) (*evaluations)++;
        } else {
            /* the load F with Σ ε_k(F)/c_k + C_b F = x, each ε_k from σ_k(ε_k) = (2c_k/S_k) F:
             * g(F) increases strictly; Newton on F, safeguarded by bisection */
            double soft = compliance;
            for (int k = 0; k < n; k++) soft += 2.0 / (S[k] * (law.two_mu + law.b));
            double scale = fmax(fabs(ch[BK_CHANNEL_F]),
                                (fabs(x[c]) + fabs(ch[BK_CHANNEL_X])) / soft);
            double lo = -INFINITY, hi = INFINITY;
            load = ch[BK_CHANNEL_F];
            int done = 0;
            for (int i = 0; i < MAX_ITERATIONS && !done; i++) {
                double g = compliance * load - x[c], dg = compliance;
                for (int k = 0; k < n; k++) {
                    double pk = 2.0 * cf[k] / S[k];
                    const double *layer = ch + BK_CHANNEL_HEAD + k * layer_size;
                    if (solve_layer(&law, layer, A[k], pk * load, eps[k], &eps[k], &slope[k],
                                    evaluations)) {
                        snprintf(text, sizeof text,
                                 "channel %s, layer %d: the layer's strain did not converge at "
                                 "load %g", CHANNEL_NAMES[c], k + 1, load);
                        return fail(message, length, text);
                    }
                    g += eps[k] / cf[k];
                    dg += pk / (cf[k] * slope[k]);
                }
                if (g == 0.0) break;
                if (g < 0.0) lo = load; else hi = load;
                double step = -g / dg, guess = bracketed(load, step, lo, hi);
                double tol = LOAD_TOLERANCE * fmax(fabs(load), scale);
                done = fabs(step) <= tol || hi - lo <= tol;
                if (!done) {
                    if (i == MAX_ITERATIONS - 1 || !isfinite(guess)) {
                        snprintf(text, sizeof text,
                                 "channel %s: the series equations did not converge in %d "
                                 "iterations (drive %g)", CHANNEL_NAMES[c], MAX_ITERATIONS, x[c]);
                        return fail(message, length, text);
                    }
                    load = guess;
                }
            }
        }
        if (!isfinite(load)) {
            snprintf(text, sizeof text, "channel %s: the force is not finite (drive %g)",
                     CHANNEL_NAMES[c], x[c]);
            return fail(message, length, text);
        }
        for (int k = 0; k < n; k++) {
            const double *layer = ch + BK_CHANNEL_HEAD + k * layer_size;
            commit_layer(&law, layer, out + BK_CHANNEL_HEAD + k * layer_size, eps[k], decay, J);
        }
        out[BK_CHANNEL_X] = x[c];
        out[BK_CHANNEL_F] = load;
        f[c] = load;
    }
    return 0;
}
