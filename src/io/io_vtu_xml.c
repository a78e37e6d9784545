/* What the VTU reader takes from expat's events: where an event is, attributes by name,
 * numbers in attributes checked, and the appended block, which is raw bytes after the XML and
 * so is found by hand. */
#include "vtu_read.h"

#include <string.h>

vtu_pos vtu_here(const reader *r)
{
    /* expat counts columns from 0; the messages count from 1, as editors do */
    vtu_pos at = {(unsigned long)XML_GetCurrentLineNumber(r->xp),
                  (unsigned long)XML_GetCurrentColumnNumber(r->xp) + 1};
    return at;
}

const char *vtu_attr(const XML_Char **atts, const char *key)
{
    for (size_t k = 0; atts[k]; k += 2)
        if (!strcmp(atts[k], key))
            return atts[k + 1];
    return NULL;
}

int vtu_get_uint(reader *r, const XML_Char **atts, const char *key, uint64_t *v, uint64_t max)
{
    const char *s = vtu_attr(atts, key);
    if (!s)
        return 0;
    const char *p = s;
    while (vtu_is_space((unsigned char)*p))
        ++p;
    uint64_t x = 0;
    int digits = 0;
    for (; *p >= '0' && *p <= '9'; ++p, ++digits) {
        if (x > (max - (uint64_t)(*p - '0')) / 10) {
            vtu_fail_at(r, vtu_here(r), "attribute %s exceeds the limit %llu", key,
                        (unsigned long long)max);
            return -1;
        }
        x = 10 * x + (uint64_t)(*p - '0');
    }
    while (vtu_is_space((unsigned char)*p))
        ++p;
    if (!digits || *p) {
        vtu_fail_at(r, vtu_here(r), "attribute %s=\"%.32s\" is not a non-negative integer", key,
                    s);
        return -1;
    }
    *v = x;
    return 1;
}

int vtu_locate_appended(reader *r, size_t tag_end, vtu_pos at)
{
    size_t q = tag_end;
    int empty = tag_end >= 2 && r->buf[tag_end - 2] == '/'; /* <AppendedData .../> */
    while (q < r->len && vtu_is_space(r->buf[q]))
        ++q;
    if (empty || q >= r->len || r->buf[q] != '_')
        return vtu_fail_at(r, at, "AppendedData does not start with '_'");
    r->have_appended = 1;
    r->data = q + 1;
    static const char end_tag[] = "</AppendedData>";
    size_t m = sizeof end_tag - 1;
    r->data_end = 0;
    for (size_t e = r->len; e >= r->data + m; --e)
        if (!memcmp(r->buf + e - m, end_tag, m)) {
            r->data_end = e - m;
            break;
        }
    if (r->data_end < r->data)
        return vtu_fail(r,
                        "truncated file: no </AppendedData> after the appended data "
                        "(which starts at byte %zu)",
                        r->data);
    return PST_OK;
}
