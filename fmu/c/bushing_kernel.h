/* The bushing as a time-domain element: the generic kernel (docs/element.md).
 *
 * Six uncoupled channels (dx dy dz rx ry rz), each a stack of rubber layers in series with an
 * optional linear bulk compliance. Each layer carries the thesis' branches: elastic 2µε(1+βε²),
 * fractional m·Σ g_j z_j (a sum of exponentials, integrated exactly for the input held over the
 * step), viscous c_v·(mean strain rate over the step) and Berg friction with its reversal
 * memory. One step costs O(layers × exponentials), whatever the length of the history.
 *
 * No FMI in here, no allocation: the caller owns every buffer (sizes from the *_count
 * functions). SI units throughout: m and rad in, N and N·m out.
 */
#ifndef BUSHING_KERNEL_H
#define BUSHING_KERNEL_H

#include <stddef.h>

#define BK_CHANNELS 6
#define BK_MAX_EXPONENTIALS 64
#define BK_MAX_LAYERS 1000
#define BK_MESSAGE 256

/* the material scalars at the start of the parameter vector */
enum { BK_MU, BK_M, BK_ALPHA, BK_SIGMA_F_MAX, BK_EPS_HALF, BK_BETA, BK_VISCOSITY, BK_SCALARS };

/* per channel: the committed drive x, load F and the last step's change of x, then per layer
 * the committed strain ε, the friction reversal point (ε_s, σ_s), the direction of motion s
 * (−1, 0 virgin, +1), the friction stress σ_f at ε, the last step's change of ε, and the
 * exponentials' states z_j (the two changes only guess the next step's solution) */
enum { BK_CHANNEL_X, BK_CHANNEL_F, BK_CHANNEL_STEP, BK_CHANNEL_HEAD };
enum { BK_LAYER_EPS, BK_LAYER_EPS_S, BK_LAYER_SIG_S, BK_LAYER_DIR, BK_LAYER_SIG_F, BK_LAYER_STEP,
       BK_LAYER_HEAD };

typedef struct {
    int exponentials;           /* J: terms of the sum of exponentials */
    int layers[BK_CHANNELS];    /* N_c: layers in series in each channel */
} bk_sizes;

/* The parameter vector: the BK_SCALARS material scalars (mu, m, alpha, sigma_f_max, eps_half,
 * beta, viscosity), rate[J], weight[J], then per channel S[N_c], c[N_c], compliance. */
size_t bk_parameter_count(const bk_sizes *sizes);
size_t bk_channel_parameters(const bk_sizes *sizes, int channel);  /* offset of channel's S[0] */
/* The state vector (doubles), as above; all zeros is the virgin state at rest. */
size_t bk_state_count(const bk_sizes *sizes);
size_t bk_channel_state(const bk_sizes *sizes, int channel);       /* offset of channel's x */
/* Scratch doubles bk_advance needs; bk_work_reset before first use and whenever the parameters
 * change (it caches e^{−λh} and the layers' constants by step size). */
size_t bk_work_count(const bk_sizes *sizes);
void bk_work_reset(const bk_sizes *sizes, double *work);

/* The readable name of parameter `index` (mu … viscosity, rate[j], weight[j], dx.S[k], dx.c[k],
 * dx.compliance …, indices from 1), as modelDescription.xml has it. */
void bk_parameter_name(const bk_sizes *sizes, size_t index, char *name, size_t length);

/* 0 when the sizes / parameters are usable, else nonzero with a sentence in message. */
int bk_check_sizes(const bk_sizes *sizes, char *message, size_t length);
int bk_check_parameters(const bk_sizes *sizes, const double *parameters, char *message,
                        size_t length);

/* One step of length h (s) with the six inputs x (m, rad) held over it: the forces f at its end
 * (N, N·m) and the state after it in `next` (which may be `state` itself: a commit; another
 * buffer: a trial that leaves `state` alone). `evaluations`, if not NULL, is increased by the
 * number of layer-law evaluations spent. 0 on success; otherwise nonzero, a sentence in
 * message, and `next` and f unspecified. */
int bk_advance(const bk_sizes *sizes, const double *parameters, const double *state,
               double *next, const double x[BK_CHANNELS], double h, double f[BK_CHANNELS],
               double *work, long *evaluations, char *message, size_t length);

#endif
