/* The XML scanner of the VTU reader: tags and their attributes as ranges of the file, comments
 * and declarations skipped, numbers in attributes checked. */
#include "vtu_read.h"

#include <stdlib.h>
#include <string.h>

static int is_name_char(int ch)
{
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
           ch == '_' || ch == ':' || ch == '.' || ch == '-';
}

int vtu_name_is(const reader *r, size_t at, size_t len, const char *s)
{
    return strlen(s) == len && memcmp(r->buf + at, s, len) == 0;
}

/* Skip to just after `end` (a NUL-free string); 0 when the file ends first. */
int vtu_skip_past(reader *r, const char *end)
{
    size_t m = strlen(end);
    for (size_t k = r->pos; k + m <= r->len; ++k)
        if (memcmp(r->buf + k, end, m) == 0) {
            r->pos = k + m;
            return 1;
        }
    return 0;
}

/* Parse the tag at r->pos (a '<' that opens an element or an end tag). */
int vtu_parse_tag(reader *r, xtag *t)
{
    const unsigned char *b = r->buf;
    size_t p = r->pos, n = r->len;
    memset(t, 0, sizeof *t);
    t->at = p++;
    if (p < n && b[p] == '/') {
        t->closing = 1;
        ++p;
    }
    t->name = p;
    while (p < n && is_name_char(b[p]))
        ++p;
    t->name_len = p - t->name;
    if (t->name_len == 0)
        return vtu_fail_at(r, t->at, "malformed XML: expected an element name after '<'");
    for (;;) {
        while (p < n && vtu_is_space(b[p]))
            ++p;
        if (p >= n)
            return vtu_fail_at(r, t->at, "truncated file: the tag <%.*s is not closed",
                               (int)(t->name_len < 64 ? t->name_len : 64),
                               (const char *)b + t->name);
        if (b[p] == '>') {
            r->pos = p + 1;
            return PST_OK;
        }
        if (!t->closing && b[p] == '/' && p + 1 < n && b[p + 1] == '>') {
            t->empty = 1;
            r->pos = p + 2;
            return PST_OK;
        }
        if (t->closing || !is_name_char(b[p]))
            return vtu_fail_at(r, p, "malformed XML: unexpected character '%c' in a tag",
                               b[p] >= 32 && b[p] < 127 ? b[p] : '?');
        if (t->nattr == MAX_ATTR)
            return vtu_fail_at(r, p, "malformed XML: more than %d attributes in one tag", MAX_ATTR);
        size_t an = p;
        while (p < n && is_name_char(b[p]))
            ++p;
        size_t an_len = p - an;
        while (p < n && vtu_is_space(b[p]))
            ++p;
        if (p >= n || b[p] != '=')
            return vtu_fail_at(r, p, "malformed XML: expected '=' after attribute %.*s",
                               (int)(an_len < 64 ? an_len : 64), (const char *)b + an);
        ++p;
        while (p < n && vtu_is_space(b[p]))
            ++p;
        if (p >= n || (b[p] != '"' && b[p] != '\''))
            return vtu_fail_at(r, p, "malformed XML: expected a quoted value of attribute %.*s",
                               (int)(an_len < 64 ? an_len : 64), (const char *)b + an);
        unsigned char q = b[p++];
        size_t av = p;
        while (p < n && b[p] != q && b[p] != '<')
            ++p;
        if (p >= n || b[p] != q)
            return vtu_fail_at(r, av - 1, "malformed XML: unterminated value of attribute %.*s",
                               (int)(an_len < 64 ? an_len : 64), (const char *)b + an);
        t->an[t->nattr] = an;
        t->an_len[t->nattr] = an_len;
        t->av[t->nattr] = av;
        t->av_len[t->nattr] = p - av;
        ++t->nattr;
        ++p;
    }
}

/* Copy attribute `key` of `t` into out (cap bytes) with the five predefined entities decoded.
 * 1: found, 0: absent, -1: too long for out. */
int vtu_get_attr(const reader *r, const xtag *t, const char *key, char *out, size_t cap)
{
    static const char *const ent[][2] = {
        {"&lt;", "<"}, {"&gt;", ">"}, {"&amp;", "&"}, {"&quot;", "\""}, {"&apos;", "'"}};
    for (int k = 0; k < t->nattr; ++k) {
        if (!vtu_name_is(r, t->an[k], t->an_len[k], key))
            continue;
        const char *v = (const char *)r->buf + t->av[k];
        size_t len = t->av_len[k], o = 0;
        for (size_t i = 0; i < len;) {
            const char *rep = NULL;
            size_t adv = 1;
            if (v[i] == '&')
                for (size_t e = 0; e < 5; ++e) {
                    size_t el = strlen(ent[e][0]);
                    if (i + el <= len && memcmp(v + i, ent[e][0], el) == 0) {
                        rep = ent[e][1];
                        adv = el;
                        break;
                    }
                }
            if (o + 1 >= cap)
                return -1;
            out[o++] = rep ? rep[0] : v[i];
            i += adv;
        }
        out[o] = '\0';
        return 1;
    }
    return 0;
}

/* An attribute parsed as a non-negative decimal integer; 1 found, 0 absent, error otherwise. */
int vtu_get_uint(reader *r, const xtag *t, const char *key, uint64_t *v, uint64_t max)
{
    char s[64];
    int got = vtu_get_attr(r, t, key, s, sizeof s);
    if (got == 0)
        return 0;
    if (got < 0) {
        vtu_fail_at(r, t->at, "attribute %s is too long", key);
        return -1;
    }
    char *p = s;
    while (vtu_is_space(*p))
        ++p;
    uint64_t x = 0;
    int digits = 0;
    for (; *p >= '0' && *p <= '9'; ++p, ++digits) {
        if (x > (max - (uint64_t)(*p - '0')) / 10) {
            vtu_fail_at(r, t->at, "attribute %s exceeds the limit %llu", key,
                        (unsigned long long)max);
            return -1;
        }
        x = 10 * x + (uint64_t)(*p - '0');
    }
    while (vtu_is_space(*p))
        ++p;
    if (!digits || *p) {
        vtu_fail_at(r, t->at, "attribute %s=\"%.32s\" is not a non-negative integer", key, s);
        return -1;
    }
    *v = x;
    return 1;
}
