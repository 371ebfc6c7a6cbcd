/* The FMU's instance and its saved states, shared by bushing_fmu.c (the FMI frame) and
 * bushing_state.c (get, set and serialize the FMU state). */
#ifndef BUSHING_FMU_H
#define BUSHING_FMU_H

#include "fmi2Functions.h"
#include "bushing_kernel.h"

typedef enum { INSTANTIATED, INITIALIZING, STEPPING, TERMINATED, FAILED } phase_t;

typedef struct {
    bk_sizes sizes;
    size_t parameters, states;
    double *p, *p_start, *state, *next, *work;  /* one block, see instantiate */
    double in[BK_CHANNELS], out[BK_CHANNELS];
    double time;
    phase_t phase;
    int logging;
    char name[128];
    fmi2CallbackFunctions cb;
} Instance;

typedef struct {  /* an fmi2FMUstate: the instance's values, no pointer into it */
    size_t parameters, states;
    double *p, *state;
    double in[BK_CHANNELS], out[BK_CHANNELS];
    double time;
    phase_t phase;
} Snapshot;

void bf_log(Instance *m, fmi2Status status, const char *category, const char *format, ...);
fmi2Status bf_error(Instance *m, const char *format, const char *detail);
void *bf_allocate(Instance *m, size_t count, size_t size);

#endif
