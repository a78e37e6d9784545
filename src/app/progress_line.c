/* The text of a progress line, fitted to the terminal's width (progress.h): a pure function
 * of its inputs, so that the fitting is tested without a terminal. */
#define _POSIX_C_SOURCE 200809L /* fileno */

#include "progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

enum { BAR_FULL = 30, BAR_MIN = 10, DETAIL_MIN = 8 };

int progress_width(void)
{
    struct winsize ws;
    if (ioctl(fileno(stderr), TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0)
        return ws.ws_col;
    const char *cols = getenv("COLUMNS");
    char *end;
    long w = cols ? strtol(cols, &end, 10) : 0;
    return cols && end != cols && *end == '\0' && w > 0 && w < 100000 ? (int)w : 80;
}

/* Columns of a UTF-8 string: its bytes but the continuation bytes. */
static size_t columns(const char *s)
{
    size_t c = 0;
    for (; *s; ++s)
        c += ((unsigned char)*s & 0xC0) != 0x80;
    return c;
}

/* Cut s after `keep` columns, never inside a character. */
static void cut(char *s, size_t keep)
{
    size_t c = 0;
    for (char *q = s; *q; ++q) {
        if (((unsigned char)*q & 0xC0) != 0x80 && c++ == keep) {
            *q = '\0';
            return;
        }
    }
}

/* A rate as "1.2e5" from 10^4 up (short at any size), else as an integer. */
static void format_rate(char *out, size_t cap, double rate, const char *unit)
{
    if (rate < 1e4) {
        snprintf(out, cap, "%.0f %s/s", rate, unit);
        return;
    }
    int e = (int)floor(log10(rate));
    double m = rate / pow(10.0, e);
    if (m >= 9.95) { /* 9.96e4 would print as 10.0e4 */
        m /= 10;
        ++e;
    }
    snprintf(out, cap, "%.1fe%d %s/s", m, e, unit);
}

/* The pieces of the line joined by single spaces, the empty ones left out. */
static void join(char *out, size_t cap, const char *const *piece, int npieces)
{
    size_t len = 0;
    out[0] = '\0';
    for (int k = 0; k < npieces; ++k) {
        if (!piece[k][0])
            continue;
        int w = snprintf(out + len, cap - len, "%s%s", len ? " " : "", piece[k]);
        if (w < 0 || (size_t)w >= cap - len)
            return; /* cut at the buffer's end; the caller cuts to the width anyway */
        len += (size_t)w;
    }
}

size_t progress_format(char *out, size_t cap, int width, const char *label, double fraction,
                       double elapsed, double rate, const char *unit, const char *detail)
{
    size_t room = width > 1 ? (size_t)width - 1 : 0;
    int known = fraction >= 0 && fraction <= 1;
    char pct[8] = "", clock[32], speed[64] = "", text[160], bar[BAR_FULL + 3] = "";
    if (known) /* rounded down: 100 % only when done */
        snprintf(pct, sizeof pct, "%3d%%", (int)floor(fraction * 100));
    snprintf(clock, sizeof clock, "%.1f s", elapsed);
    if (unit && rate > 0 && isfinite(rate))
        format_rate(speed, sizeof speed, rate, unit);
    snprintf(text, sizeof text, "%s", detail ? detail : "");
    const char *piece[] = {label, bar, pct, clock, speed, text};
    /* the line without its bar, then the bar in what room is left */
    join(out, cap, piece, 6);
    size_t used = columns(out);
    if (known && used + 3 + BAR_MIN <= room) {
        size_t len = used + 3 + BAR_FULL <= room ? BAR_FULL : room - used - 3;
        size_t full = (size_t)floor(fraction * (double)len + 0.5);
        bar[0] = '[';
        for (size_t k = 0; k < len; ++k)
            bar[1 + k] = k < full ? '#' : '.';
        bar[len + 1] = ']';
        bar[len + 2] = '\0';
        join(out, cap, piece, 6);
        return columns(out);
    }
    if (used > room && text[0]) { /* cut the detail, or drop it when little would be left */
        size_t others = used - columns(text);
        if (others + DETAIL_MIN <= room)
            cut(text, room - others);
        else
            text[0] = '\0';
        join(out, cap, piece, 6);
    }
    char *const dropped[] = {speed, clock}; /* in this order */
    for (int k = 0; k < 2 && columns(out) > room; ++k) {
        dropped[k][0] = '\0';
        join(out, cap, piece, 6);
    }
    cut(out, room);
    return columns(out);
}
