/* The bushing as an FMI 2.0 co-simulation FMU: the frame around the generic kernel
 * (bushing_kernel.c) and its resource file (bushing_resource.c). docs/fmu.md tells the story.
 *
 * Value references: 0–5 the inputs dx dy dz rx ry rz (m, rad), 6–11 the outputs fx fy fz
 * mx my mz (N, N·m), then the kernel's parameters in its order (bushing_kernel.h). The inputs
 * are held over a step; the outputs after fmi2DoStep are the forces at its end. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "bushing_kernel.h"
#include "bushing_resource.h"
#include "bushing_fmu.h"

#define VR_INPUTS 0
#define VR_OUTPUTS BK_CHANNELS
#define VR_PARAMETERS (2 * BK_CHANNELS)

void bf_log(Instance *m, fmi2Status status, const char *category, const char *format,
                        ...)
{
    char text[512];
    va_list args;
    if (!m || !m->cb.logger) return;
    if (status == fmi2OK && !m->logging) return;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    m->cb.logger(m->cb.componentEnvironment, m->name, status, category, "%s", text);
}

fmi2Status bf_error(Instance *m, const char *format, const char *detail)
{
    bf_log(m, fmi2Error, "logStatusError", format, detail);
    return fmi2Error;
}

void *bf_allocate(Instance *m, size_t count, size_t size)
{
    return m->cb.allocateMemory(count, size);
}

/* ------------------------------------------------------------------------------------------ */

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn,
                                           size_t nCategories, const fmi2String categories[])
{
    (void)nCategories;
    (void)categories;
    if (!c) return fmi2Error;
    ((Instance *)c)->logging = loggingOn;
    return fmi2OK;
}

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                          fmi2String fmuGUID, fmi2String fmuResourceLocation,
                                          const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Instance probe, *m;
    char path[4096], guid[BR_GUID], message[BK_MESSAGE + 4200];
    bk_sizes sizes;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    memset(&probe, 0, sizeof probe);  /* a stand-in to log through until the instance exists */
    probe.cb = *functions;
    snprintf(probe.name, sizeof probe.name, "%s", instanceName ? instanceName : "bushing");
    if (fmuType != fmi2CoSimulation) {
        bf_error(&probe, "%s", "this FMU is for co-simulation only");
        return NULL;
    }
    if (br_path_from_uri(fmuResourceLocation, path, sizeof path - sizeof BR_FILE - 1)) {
        bf_error(&probe, "the resource location %s is no local file URI",
              fmuResourceLocation ? fmuResourceLocation : "(null)");
        return NULL;
    }
    if (path[0] && path[strlen(path) - 1] != '/') strcat(path, "/");
    strcat(path, BR_FILE);
    if (br_read(path, guid, &sizes, NULL, message, sizeof message)) {
        bf_error(&probe, "%s", message);
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, guid)) {
        bf_error(&probe, "the GUID does not match the resource file's (%s)", guid);
        return NULL;
    }
    m = bf_allocate(&probe, 1, sizeof(Instance));
    if (!m) return NULL;
    memcpy(m, &probe, sizeof probe);
    m->sizes = sizes;
    m->parameters = bk_parameter_count(&sizes);
    m->states = bk_state_count(&sizes);
    m->p = bf_allocate(m, 2 * m->parameters + 2 * m->states + bk_work_count(&sizes), sizeof(double));
    if (!m->p) {
        functions->freeMemory(m);
        return NULL;
    }
    m->p_start = m->p + m->parameters;
    m->state = m->p_start + m->parameters;
    m->next = m->state + m->states;
    m->work = m->next + m->states;
    if (br_read(path, guid, &sizes, m->p_start, message, sizeof message)) {
        bf_error(&probe, "%s", message);
        functions->freeMemory(m->p);
        functions->freeMemory(m);
        return NULL;
    }
    memcpy(m->p, m->p_start, m->parameters * sizeof(double));
    bk_work_reset(&sizes, m->work);
    m->logging = loggingOn;
    m->phase = INSTANTIATED;
    bf_log(m, fmi2OK, "logAll", "instantiated from %s", path);
    return m;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c)
{
    Instance *m = c;
    if (!m) return;
    m->cb.freeMemory(m->p);
    m->cb.freeMemory(m);
}

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                                           fmi2Real tolerance, fmi2Real startTime,
                                           fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance *m = c;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (!m) return fmi2Error;
    if (m->phase != INSTANTIATED) return bf_error(m, "%s", "fmi2SetupExperiment after instantiation only");
    m->time = startTime;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance *m = c;
    if (!m) return fmi2Error;
    if (m->phase != INSTANTIATED) return bf_error(m, "%s", "fmi2EnterInitializationMode: not instantiated");
    m->phase = INITIALIZING;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *m = c;
    char message[BK_MESSAGE];
    if (!m) return fmi2Error;
    if (m->phase != INITIALIZING) return bf_error(m, "%s", "fmi2ExitInitializationMode: not initializing");
    if (bk_check_parameters(&m->sizes, m->p, message, sizeof message)) {
        m->phase = FAILED;
        return bf_error(m, "parameter %s", message);
    }
    memset(m->state, 0, m->states * sizeof(double));  /* at rest, virgin */
    memset(m->out, 0, sizeof m->out);
    bk_work_reset(&m->sizes, m->work);
    m->phase = STEPPING;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance *m = c;
    if (!m) return fmi2Error;
    m->phase = TERMINATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *m = c;
    if (!m) return fmi2Error;
    memcpy(m->p, m->p_start, m->parameters * sizeof(double));
    memset(m->state, 0, m->states * sizeof(double));
    memset(m->in, 0, sizeof m->in);
    memset(m->out, 0, sizeof m->out);
    bk_work_reset(&m->sizes, m->work);
    m->time = 0.0;
    m->phase = INSTANTIATED;
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* values */

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   fmi2Real value[])
{
    Instance *m = c;
    if (!m) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < VR_OUTPUTS) value[i] = m->in[r - VR_INPUTS];
        else if (r < VR_PARAMETERS) value[i] = m->out[r - VR_OUTPUTS];
        else if (r - VR_PARAMETERS < m->parameters) value[i] = m->p[r - VR_PARAMETERS];
        else {
            char text[32];
            snprintf(text, sizeof text, "%u", r);
            return bf_error(m, "fmi2GetReal: no variable has the value reference %s", text);
        }
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Real value[])
{
    Instance *m = c;
    char name[64];
    if (!m) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < VR_OUTPUTS) {
            m->in[r - VR_INPUTS] = value[i];  /* checked when a step uses it */
        } else if (r < VR_PARAMETERS) {
            return bf_error(m, "%s", "fmi2SetReal: the outputs fx … mz cannot be set");
        } else if (r - VR_PARAMETERS < m->parameters) {
            if (m->phase != INSTANTIATED && m->phase != INITIALIZING) {
                bk_parameter_name(&m->sizes, r - VR_PARAMETERS, name, sizeof name);
                return bf_error(m, "fmi2SetReal: %s is a fixed parameter, set before initialization "
                                "only", name);
            }
            m->p[r - VR_PARAMETERS] = value[i];  /* checked at fmi2ExitInitializationMode */
        } else {
            char text[32];
            snprintf(text, sizeof text, "%u", r);
            return bf_error(m, "fmi2SetReal: no variable has the value reference %s", text);
        }
    }
    return fmi2OK;
}

static fmi2Status no_such(fmi2Component c, size_t nvr, const char *what)
{
    if (!c) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return bf_error(c, "%s: the bushing has only Real variables", what);
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                      fmi2Integer value[])
{
    (void)vr;
    (void)value;
    return no_such(c, nvr, "fmi2GetInteger");
}
FMI2_Export fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                      fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return no_such(c, nvr, "fmi2GetBoolean");
}
FMI2_Export fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                     fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_such(c, nvr, "fmi2GetString");
}
FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                      const fmi2Integer value[])
{
    (void)vr;
    (void)value;
    return no_such(c, nvr, "fmi2SetInteger");
}
FMI2_Export fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                      const fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return no_such(c, nvr, "fmi2SetBoolean");
}
FMI2_Export fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                     const fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_such(c, nvr, "fmi2SetString");
}

FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c,
        const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    if (!c) return fmi2Error;
    return bf_error(c, "%s", "directional derivatives are not provided");
}

/* ------------------------------------------------------------------------------------------ */
/* co-simulation */

FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component c,
        const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
        const fmi2Real value[])
{
    (void)vr;
    (void)order;
    (void)value;
    if (!c) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return bf_error(c, "%s", "the inputs are held over a step: no input derivatives "
                          "(canInterpolateInputs is false)");
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c,
        const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    (void)vr;
    (void)order;
    (void)value;
    if (!c) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return bf_error(c, "%s", "no output derivatives (maxOutputDerivativeOrder is 0)");
}

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize,
                                  fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Instance *m = c;
    char message[BK_MESSAGE];
    double f[BK_CHANNELS];
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!m) return fmi2Error;
    if (m->phase != STEPPING) return bf_error(m, "%s", "fmi2DoStep: not initialized, or failed");
    if (bk_advance(&m->sizes, m->p, m->state, m->next, m->in, communicationStepSize, f, m->work,
                   NULL, message, sizeof message)) {
        char text[BK_MESSAGE + 64];
        snprintf(text, sizeof text, "%s (the step at t = %g s)", message, currentCommunicationPoint);
        return bf_error(m, "fmi2DoStep: %s", text);  /* the state is left as it was */
    }
    memcpy(m->state, m->next, m->states * sizeof(double));
    memcpy(m->out, f, sizeof f);
    m->time = currentCommunicationPoint + communicationStepSize;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c)
{
    if (!c) return fmi2Error;
    return bf_error(c, "%s", "fmi2CancelStep: steps are never asynchronous");
}

FMI2_Export fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    if (!c || !value) return fmi2Error;
    *value = fmi2OK;  /* no step is ever pending */
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *m = c;
    if (!m || !value) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = m->time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Integer *value)
{
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Boolean *value)
{
    Instance *m = c;
    if (!m || !value) return fmi2Error;
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s,
                                           fmi2String *value)
{
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}
