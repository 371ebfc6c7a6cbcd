/* The bushing as a time-domain element: the generic kernel. See bushing_kernel.h and
 * docs/element.md (the model, the held-input step, the series equations). The layers' law and
 * the series solves are in bushing_series.c. */
#include "bushing_kernel.h"
#include "bushing_series.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define GUESS_RATIO 2.0        /* the last step's changes guess the next within this ratio */

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

/* work: [h of the cache, B of the cache, e^{−λ_j h} (J), m g_j e^{−λ_j h} (J), each channel's
 * elastic stiffness, per layer of every channel 2c/S, S/(2c), c and 1/c, then a bs_layer per
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
           + BS_LAYER_DOUBLES * (size_t)widest;
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
    bs_layer *L = (bs_layer *)(pc + 4 * all_layers(sizes));
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
    double smax = p[BK_SIGMA_F_MAX], ehalf = p[BK_EPS_HALF];
    bs_law law = {2.0 * p[BK_MU], p[BK_BETA], work[WORK_B], smax, smax > 0.0 ? ehalf / smax : 0.0,
                  ehalf};
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
            f[c] = bs_direct(&law, ch + BK_CHANNEL_HEAD, out + BK_CHANNEL_HEAD, x[c], pc, gd, decay,
                             J);
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
        bs_prepare(L, n, &law, ch + BK_CHANNEL_HEAD, layer_size, pc, gd, J);
        pc += 4 * n;
        double scale = bs_larger(fabs(load), (fabs(x[c]) + fabs(ch[BK_CHANNEL_X])) * stiff[c]);
        double change = x[c] - ch[BK_CHANNEL_X], ratio = change / ch[BK_CHANNEL_STEP];
        if (!(fabs(ratio) <= GUESS_RATIO)) ratio = 0.0;  /* also 0/0: held, or from rest */
#ifndef BK_SERIES_NESTED_ONLY
        if (bs_newton(&law, L, ch + BK_CHANNEL_HEAD, layer_size, n, compliance, x[c], ratio, scale,
                      &load, evaluations))
#endif
        {
            load = ch[BK_CHANNEL_F];
            if (bs_nested(&law, L, n, compliance, x[c], scale, &load, evaluations, why,
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
        bs_commit(L, n, ch + BK_CHANNEL_HEAD, out + BK_CHANNEL_HEAD, layer_size, decay, J);
        out[BK_CHANNEL_STEP] = x[c] - ch[BK_CHANNEL_X];
        out[BK_CHANNEL_X] = x[c];
        out[BK_CHANNEL_F] = load;
        f[c] = load;
    }
    return 0;
}
