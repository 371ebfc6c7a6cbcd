/* The FMU's resource file: the design's coefficients the generic kernel starts from, and the
 * resource location URI (RFC 8089 file URIs) that says where it is. No FMI in here. */
#ifndef BUSHING_RESOURCE_H
#define BUSHING_RESOURCE_H

#include <stddef.h>

#include "bushing_kernel.h"

#define BR_FILE "coefficients.txt"
#define BR_VERSION 1
#define BR_GUID 128

/* The local path of a file URI: file:///path, file:/path, file://localhost/path,
 * file://host/path (the authority is dropped), %XX decoded. 0 on success. */
int br_path_from_uri(const char *uri, char *path, size_t length);

/* Read the coefficients file at `path`: its GUID and sizes; and, when `values` is not NULL,
 * the bk_parameter_count(sizes) parameter values, each line's name checked against
 * bk_parameter_name. 0 on success, else nonzero with a sentence in message. */
int br_read(const char *path, char guid[BR_GUID], bk_sizes *sizes, double *values,
            char *message, size_t length);

#endif
