/* The progress line's fitting (progress_format, src/app/progress.h): the full line where it
 * fits, the bar shrunk and then dropped, the detail cut and then dropped, the rate and the
 * clock dropped, and never more than width - 1 columns, UTF-8 never cut inside a character. */
#include "check.h"
#include "progress.h"

#include <stdio.h>
#include <string.h>

/* Columns of a UTF-8 string (bytes but continuation bytes). */
static size_t cols(const char *s)
{
    size_t c = 0;
    for (; *s; ++s)
        c += ((unsigned char)*s & 0xC0) != 0x80;
    return c;
}

/* 1 when s ends with a whole UTF-8 character. */
static int whole_utf8(const char *s)
{
    size_t n = strlen(s), k = n;
    while (k > 0 && ((unsigned char)s[k - 1] & 0xC0) == 0x80)
        --k;
    if (k == 0)
        return n == 0;
    unsigned char lead = (unsigned char)s[k - 1];
    size_t need = lead < 0x80 ? 1 : lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : 2;
    return n - (k - 1) == need;
}

static void check_is(int width, const char *label, double f, double t, double rate,
                     const char *unit, const char *detail, const char *want)
{
    char out[512];
    size_t c = progress_format(out, sizeof out, width, label, f, t, rate, unit, detail);
    CHECK(strcmp(out, want) == 0);
    CHECK_INT(c, cols(want));
    if (strcmp(out, want) != 0)
        fprintf(stderr, "  got  '%s'\n  want '%s'\n", out, want);
}

int main(void)
{
    /* room for everything: a 30-column bar */
    check_is(80, "neighbours", 0.5, 12.34, 123456, "rows", "",
             "neighbours [###############...............]  50% 12.3 s 1.2e5 rows/s");
    /* a shrunk bar: 49 columns of room, 35 without the bar, so 11 cells */
    check_is(50, "neighbours", 0.5, 12.34, 123456, "rows", "",
             "neighbours [######.....]  50% 12.3 s 1.2e5 rows/s");
    /* less than a 10-cell bar's room: no bar */
    check_is(40, "neighbours", 0.5, 12.34, 123456, "rows", "",
             "neighbours  50% 12.3 s 1.2e5 rows/s");
    /* rounded down: 100 % only when done; the rate just under 10^5 carries over */
    check_is(40, "precompute", 0.999, 1.0, 99600, "rows", "",
             "precompute  99% 1.0 s 1.0e5 rows/s");
    check_is(80, "task u", -1, 0.04, 0, "rows", "", "task u 0.0 s");
    check_is(80, "solve", -1, 2.0, 532, "it", "", "solve 2.0 s 532 it/s");
    /* the detail is cut to the room left, then dropped, then the rate, then the clock */
    check_is(40, "sweep", -1, 3.0, 0, NULL, "run 3/10: cloud.spacing=0.01 scheme=qsfdi",
             "sweep 3.0 s run 3/10: cloud.spacing=0.0");
    check_is(20, "sweep", -1, 3.0, 0, NULL, "run 3/10: cloud.spacing=0.01", "sweep 3.0 s");
    check_is(23, "neighbours", 0.25, 3.0, 2e5, "rows", "", "neighbours  25% 3.0 s");
    check_is(20, "neighbours", 0.25, 3.0, 2e5, "rows", "", "neighbours  25%");
    check_is(12, "neighbours", 0.25, 3.0, 2e5, "rows", "", "neighbours ");
    check_is(1, "neighbours", 0.25, 3.0, 2e5, "rows", "", "");
    check_is(0, "neighbours", 0.25, 3.0, 2e5, "rows", "", "");
    /* the lines the issue saw wrap: at 80 and 160 columns every line fits in width - 1 */
    static const int widths[] = {80, 160, 24, 7};
    char detail[200], out[512];
    memset(detail, 'x', sizeof detail - 1);
    detail[sizeof detail - 1] = '\0';
    for (size_t w = 0; w < sizeof widths / sizeof *widths; ++w)
        for (int f = -1; f <= 10; ++f) {
            progress_format(out, sizeof out, widths[w], "sweep", f / 10.0, 1234.5, 1e7, "runs",
                            detail);
            CHECK(cols(out) <= (size_t)widths[w] - 1);
        }
    /* UTF-8 in a detail (a scene's value) is cut between characters, counted by columns */
    const char *accents = "temp\xc3\xa9rature \xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9";
    for (int w = 20; w <= 40; ++w) {
        progress_format(out, sizeof out, w, "task", -1, 1.0, 0, NULL, accents);
        CHECK(cols(out) <= (size_t)w - 1);
        CHECK(whole_utf8(out));
    }
    /* a small buffer: cut, never overrun */
    char small[16];
    progress_format(small, sizeof small, 80, "neighbours", 0.5, 1.0, 1e5, "rows", "detail");
    CHECK(strlen(small) < sizeof small);
    return check_summary("test_progress_line");
}
