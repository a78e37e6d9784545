/* The worker side of a sweep's runs at once (sweep_jobs.c, docs/sweeps.md "Runs at once"):
 * read "K\n" from the socket, run combination K here, answer one line of compact JSON
 * {"k", "ran", "status", "message", "report"}; stop at the end of the input. */
#define _POSIX_C_SOURCE 200809L /* ssize_t, read, write */

#include "sweep_jobs.h"

#include "sweep_grid.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Numbers become strings in place (their keys stay), with cJSON's allocator. */
void sweep_report_encode(cJSON *r)
{
    for (cJSON *c = r ? r->child : NULL; c; c = c->next) {
        char t[40];
        if (!cJSON_IsNumber(c)) {
            sweep_report_encode(c);
        } else if (snprintf(t, sizeof t, "pst:%.17g", c->valuedouble) > 0 &&
                   (c->valuestring = cJSON_malloc(strlen(t) + 1))) {
            memcpy(c->valuestring, t, strlen(t) + 1);
            c->type = cJSON_String;
        }
    }
}

void sweep_report_decode(cJSON *r)
{
    for (cJSON *c = r ? r->child : NULL; c; c = c->next) {
        const char *t = cJSON_GetStringValue(c);
        if (t && strncmp(t, "pst:", 4) == 0) {
            double v = strtod(t + 4, NULL);
            cJSON_free(c->valuestring);
            c->valuestring = NULL;
            c->type = cJSON_Number;
            cJSON_SetNumberValue(c, v);
        } else {
            sweep_report_decode(c);
        }
    }
}

/* The next line of fd into line (without its newline): 1, or 0 at the end of the input or on
 * an error. */
static int read_line(int fd, char *line, size_t cap)
{
    size_t n = 0;
    for (;;) {
        char ch;
        ssize_t r = read(fd, &ch, 1);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return 0;
        if (ch == '\n')
            break;
        if (n + 1 < cap)
            line[n++] = ch;
    }
    line[n] = '\0';
    return 1;
}

static int write_all(int fd, const char *p, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* The answer line of combination k. */
static char *answer(size_t k, int ran, int status, const char *msg, cJSON *report)
{
    cJSON *a = cJSON_CreateObject();
    sweep_report_encode(report);
    if (!a || !cJSON_AddItemToObject(a, "report", report ? report : cJSON_CreateNull())) {
        cJSON_Delete(a);
        cJSON_Delete(report);
        return NULL;
    }
    if (!cJSON_AddNumberToObject(a, "k", (double)k) ||
        !cJSON_AddBoolToObject(a, "ran", ran) ||
        !cJSON_AddNumberToObject(a, "status", status) ||
        !cJSON_AddStringToObject(a, "message", msg)) {
        cJSON_Delete(a);
        return NULL;
    }
    char *line = cJSON_PrintUnformatted(a); /* one line: strings escape their newlines */
    cJSON_Delete(a);                        /* and the report with it */
    return line;
}

int pst_sweep_serve(const pst_sweep *sw, const char *digest, const pst_sweep_opts *o, int fd,
                    char *err, size_t errlen)
{
    char mine[32];
    snprintf(mine, sizeof mine, "%016llx", (unsigned long long)sweep_digest(sw));
    if (strcmp(mine, digest) != 0) {
        snprintf(err, errlen, "%s is not the sweep this worker was started for (the file "
                              "changed since the sweep started?)", sw->path);
        return PST_EINPUT;
    }
    char line[64];
    while (read_line(fd, line, sizeof line)) {
        char *end;
        errno = 0;
        unsigned long long k = strtoull(line, &end, 10);
        if (errno || end == line || *end || k >= sw->ncombos) {
            snprintf(err, errlen, "'%.32s' is not a combination of %s", line, sw->path);
            return PST_EINPUT;
        }
        cJSON *rep;
        char msg[PST_ERRLEN * 2] = "";
        int ran, rs = sweep_run_one(sw, o, (size_t)k, &ran, &rep, msg, sizeof msg);
        char *out = answer((size_t)k, ran, rs, msg, rep);
        if (!out) {
            snprintf(err, errlen, "out of memory for the answer of combination %llu", k);
            return PST_ENOMEM;
        }
        size_t n = strlen(out);
        out[n] = '\n'; /* over the terminator: the line goes out by length */
        int wr = write_all(fd, out, n + 1);
        free(out);
        if (wr != 0) {
            snprintf(err, errlen, "the sweep is gone: %s", strerror(errno));
            return PST_EIO;
        }
    }
    return PST_OK;
}
