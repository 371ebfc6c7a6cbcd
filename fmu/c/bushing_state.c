/* The FMU state of the bushing: get, set, free and (de)serialize it. A state is a copy of the
 * instance's values, never of its pointers (the crash of modelica/Reference-FMUs#635). */
#include <string.h>

#include "bushing_fmu.h"

#define STATE_MAGIC "BUSHFMU"  /* 8 bytes with its terminator */
#define STATE_VERSION 2u  /* 2: the last step's changes of the drive and of each layer's strain (the Newton's first guess) */

static Snapshot *new_snapshot(Instance *m)
{
    Snapshot *s = bf_allocate(m, 1, sizeof(Snapshot));
    if (!s) return NULL;
    s->p = bf_allocate(m, m->parameters + m->states, sizeof(double));
    if (!s->p) {
        m->cb.freeMemory(s);
        return NULL;
    }
    s->state = s->p + m->parameters;
    s->parameters = m->parameters;
    s->states = m->states;
    return s;
}

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *m = c;
    Snapshot *s;
    if (!m || !FMUstate) return fmi2Error;
    s = *FMUstate ? *FMUstate : new_snapshot(m);
    if (!s) return bf_error(m, "%s", "fmi2GetFMUstate: out of memory");
    memcpy(s->p, m->p, m->parameters * sizeof(double));
    memcpy(s->state, m->state, m->states * sizeof(double));
    memcpy(s->in, m->in, sizeof m->in);
    memcpy(s->out, m->out, sizeof m->out);
    s->time = m->time;
    s->phase = m->phase;
    *FMUstate = s;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    Instance *m = c;
    Snapshot *s = FMUstate;
    if (!m || !s) return fmi2Error;
    if (s->parameters != m->parameters || s->states != m->states)
        return bf_error(m, "%s", "fmi2SetFMUstate: the state is of another bushing");
    memcpy(m->p, s->p, m->parameters * sizeof(double));
    memcpy(m->state, s->state, m->states * sizeof(double));
    memcpy(m->in, s->in, sizeof m->in);
    memcpy(m->out, s->out, sizeof m->out);
    m->time = s->time;
    m->phase = s->phase;
    bk_work_reset(&m->sizes, m->work);  /* the parameters may have changed */
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *m = c;
    Snapshot *s;
    if (!m || !FMUstate) return fmi2Error;
    s = *FMUstate;
    if (s) {
        m->cb.freeMemory(s->p);
        m->cb.freeMemory(s);
    }
    *FMUstate = NULL;
    return fmi2OK;
}

/* the serialized state: "BUSHFMU\0", then unsigned 32-bit version, phase, J and the six layer
 * counts, then doubles: time, inputs, outputs, parameters, states (this machine's byte order:
 * a state loads in another process on the same platform) */
#define HEADER_WORDS (3 + BK_CHANNELS)
#define HEADER_BYTES (8 + HEADER_WORDS * 4)

static size_t serialized_size(const Instance *m)
{
    return HEADER_BYTES + (1 + 2 * BK_CHANNELS + m->parameters + m->states) * sizeof(double);
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate,
                                                  size_t *size)
{
    (void)FMUstate;
    if (!c || !size) return fmi2Error;
    *size = serialized_size(c);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                             fmi2Byte serializedState[], size_t size)
{
    Instance *m = c;
    Snapshot *s = FMUstate;
    unsigned int header[HEADER_WORDS];
    char *at = serializedState;
    if (!m || !s) return fmi2Error;
    if (size < serialized_size(m)) return bf_error(m, "%s", "fmi2SerializeFMUstate: buffer too small");
    header[0] = STATE_VERSION;
    header[1] = (unsigned int)s->phase;
    header[2] = (unsigned int)m->sizes.exponentials;
    for (int k = 0; k < BK_CHANNELS; k++) header[3 + k] = (unsigned int)m->sizes.layers[k];
    memcpy(at, STATE_MAGIC, 8);
    memcpy(at + 8, header, sizeof header);
    at += HEADER_BYTES;
    memcpy(at, &s->time, sizeof(double));
    at += sizeof(double);
    memcpy(at, s->in, sizeof s->in);
    at += sizeof s->in;
    memcpy(at, s->out, sizeof s->out);
    at += sizeof s->out;
    memcpy(at, s->p, (m->parameters + m->states) * sizeof(double));
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                               size_t size, fmi2FMUstate *FMUstate)
{
    Instance *m = c;
    Snapshot *s;
    unsigned int header[HEADER_WORDS];
    const char *at = serializedState;
    if (!m || !FMUstate || !serializedState) return fmi2Error;
    if (size != serialized_size(m) || memcmp(at, STATE_MAGIC, 8))
        return bf_error(m, "%s", "fmi2DeSerializeFMUstate: not a serialized state of this bushing");
    memcpy(header, at + 8, sizeof header);
    if (header[0] != STATE_VERSION)
        return bf_error(m, "%s", "fmi2DeSerializeFMUstate: a state of another version");
    if (header[1] > FAILED || (int)header[2] != m->sizes.exponentials)
        return bf_error(m, "%s", "fmi2DeSerializeFMUstate: the state is of another bushing");
    for (int k = 0; k < BK_CHANNELS; k++)
        if ((int)header[3 + k] != m->sizes.layers[k])
            return bf_error(m, "%s", "fmi2DeSerializeFMUstate: the state is of another bushing");
    s = *FMUstate ? *FMUstate : new_snapshot(m);
    if (!s) return bf_error(m, "%s", "fmi2DeSerializeFMUstate: out of memory");
    at += HEADER_BYTES;
    s->phase = (phase_t)header[1];
    memcpy(&s->time, at, sizeof(double));
    at += sizeof(double);
    memcpy(s->in, at, sizeof s->in);
    at += sizeof s->in;
    memcpy(s->out, at, sizeof s->out);
    at += sizeof s->out;
    memcpy(s->p, at, (m->parameters + m->states) * sizeof(double));
    *FMUstate = s;
    return fmi2OK;
}

