/* The FMU's resource file and its location URI. See bushing_resource.h. */
#include "bushing_resource.h"

#include <ctype.h>
#include <locale.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int hex(int c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

int br_path_from_uri(const char *uri, char *path, size_t length)
{
    const char *at;
    size_t n = 0;
    if (!uri || !path || length == 0) return 1;
    for (int i = 0; i < 5; i++)
        if (tolower((unsigned char)uri[i]) != "file:"[i]) return 1;
    at = uri + 5;
    if (at[0] == '/' && at[1] == '/') {  /* an authority: empty, localhost or a host */
        at += 2;
        while (*at && *at != '/') at++;
    }
    if (*at != '/') return 1;  /* only absolute paths */
#ifdef _WIN32
    if (isalpha((unsigned char)at[1]) && (at[2] == ':' || at[2] == '|')) at++;  /* /C:/… */
#endif
    while (*at) {
        int c = (unsigned char)*at++;
        if (c == '%') {
            int h1 = hex((unsigned char)at[0]), h2 = h1 < 0 ? -1 : hex((unsigned char)at[1]);
            if (h1 < 0 || h2 < 0) return 1;
            c = 16 * h1 + h2;
            at += 2;
            if (c == 0) return 1;
        } else if (c == '?' || c == '#') {
            break;  /* a query or fragment is no part of the path */
        }
        if (n + 1 >= length) return 1;
        path[n++] = (char)c;
    }
    path[n] = '\0';
    return 0;
}

static int complain(char *message, size_t length, const char *path, const char *what)
{
    if (message && length) snprintf(message, length, "%s: %s", path, what);
    return 1;
}

int br_read(const char *path, char guid[BR_GUID], bk_sizes *sizes, double *values,
            char *message, size_t length)
{
    char word[96], expected[96];
    int version = 0, status = 1;
    FILE *file = fopen(path, "r");
    if (!file) return complain(message, length, path, "cannot be opened");
    if (fscanf(file, "%95s %d", word, &version) != 2 || strcmp(word, "bushing-fmu-coefficients")
        || version != BR_VERSION) {
        complain(message, length, path, "is no bushing coefficients file of version 1");
        goto done;
    }
    if (fscanf(file, "%95s %127s", word, guid) != 2 || strcmp(word, "guid")) {
        complain(message, length, path, "has no guid line");
        goto done;
    }
    if (fscanf(file, "%95s %d", word, &sizes->exponentials) != 2 || strcmp(word, "exponentials")) {
        complain(message, length, path, "has no exponentials line");
        goto done;
    }
    if (fscanf(file, "%95s", word) != 1 || strcmp(word, "layers")) {
        complain(message, length, path, "has no layers line");
        goto done;
    }
    for (int c = 0; c < BK_CHANNELS; c++) {
        if (fscanf(file, "%d", &sizes->layers[c]) != 1) {
            complain(message, length, path, "has a short layers line");
            goto done;
        }
    }
    if (bk_check_sizes(sizes, message, length)) goto done;
    if (values) {
        size_t count = bk_parameter_count(sizes);
        for (size_t i = 0; i < count; i++) {
            char number[64], *end;
            bk_parameter_name(sizes, i, expected, sizeof expected);
            if (fscanf(file, "%95s %63s", word, number) != 2 || strcmp(word, expected)) {
                char text[160];
                snprintf(text, sizeof text, "expected the line of %s", expected);
                complain(message, length, path, text);
                goto done;
            }
            /* written with '.': the host's locale may want another decimal point */
            char *dot = strchr(number, '.');
            if (dot) *dot = localeconv()->decimal_point[0];
            values[i] = strtod(number, &end);
            if (*end != '\0') {
                char text[256];
                snprintf(text, sizeof text, "%s: %s is no number", expected, number);
                complain(message, length, path, text);
                goto done;
            }
        }
    }
    status = 0;
done:
    fclose(file);
    return status;
}
