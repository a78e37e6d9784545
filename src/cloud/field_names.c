/* Many field names at once: a repeated name found by sorting (n log n, where a pairwise check
 * took minutes for a file with 100 000 columns), and fields added in one step with one growth
 * of the cloud's arrays. The CSV and VTU readers go through here. */
#include "cloud_layout.h"
#include "check.h"

#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *name;
    size_t index;
} named;

/* By name, then by position: equal names sit together, earliest first. */
static int cmp_named(const void *pa, const void *pb)
{
    const named *a = pa, *b = pb;
    int c = strcmp(a->name, b->name);
    return c ? c : (a->index > b->index) - (a->index < b->index);
}

int pst_find_repeated_name(const char *const *names, size_t n, size_t *first, size_t *again)
{
    if (n < 2)
        return 0;
    named *s = malloc(n * sizeof *s);
    if (!s)
        return PST_ENOMEM;
    for (size_t k = 0; k < n; ++k)
        s[k] = (named){names[k], k};
    qsort(s, n, sizeof *s, cmp_named);
    int found = 0;
    for (size_t k = 1; k < n; ++k) {
        /* the second of a run of equal names is that name's earliest repeat; keep the
         * earliest repeat of all, as a scan in order would find it */
        int starts_run = k < 2 || strcmp(s[k - 2].name, s[k].name) != 0;
        if (starts_run && strcmp(s[k - 1].name, s[k].name) == 0 &&
            (!found || s[k].index < *again)) {
            *first = s[k - 1].index;
            *again = s[k].index;
            found = 1;
        }
    }
    free(s);
    return found;
}

/* Every name valid, none repeating a field of the cloud or an earlier name: one search by
 * sorting over the cloud's names followed by the new ones. */
static int check_new_names(const pst_cloud *c, const char *const *names, size_t n, char *err)
{
    for (size_t k = 0; k < n; ++k)
        PST_CHECK(!names[k] || !pst_is_identifier(names[k]) || pst_is_reserved_column(names[k]),
                  PST_EINVAL, err, "invalid field name '%s' (a C identifier, not a reserved column)",
                  names[k] ? names[k] : "(null)");
    size_t all = c->nfields + n;
    const char **list = malloc((all ? all : 1) * sizeof *list);
    PST_CHECK_ALLOC(list, err, "out of memory for %zu field names", all);
    for (size_t k = 0; k < c->nfields; ++k)
        list[k] = c->field_name[k];
    for (size_t k = 0; k < n; ++k)
        list[c->nfields + k] = names[k];
    size_t a, b;
    int found = pst_find_repeated_name(list, all, &a, &b);
    const char *repeated = found > 0 ? list[b] : NULL;
    free(list);
    PST_CHECK(found < 0, PST_ENOMEM, err, "out of memory for %zu field names", all);
    PST_CHECK(found, PST_EINVAL, err, "field '%s' already exists", repeated);
    return PST_OK;
}

int pst_cloud_add_fields(pst_cloud *c, const char *const *names, size_t n, double **data,
                         char *err)
{
    PST_TRY(check_new_names(c, names, n, err));
    if (n == 0)
        return PST_OK;
    size_t total = c->nfields + n;
    char(*fn)[PST_MAX_NAME] = realloc(c->field_name, total * sizeof *fn);
    if (fn)
        c->field_name = fn;
    double **fv = realloc(c->field, total * sizeof *fv);
    if (fv)
        c->field = fv;
    PST_CHECK(!fn || !fv, PST_ENOMEM, err, "out of memory for %zu fields", total);
    for (size_t k = 0; k < n; ++k) {
        double *a = pst_calloc(c->n, sizeof(double));
        PST_CHECK(!a, PST_ENOMEM, err, "field '%s': out of memory for %zu values", names[k],
                  c->n);
        snprintf(c->field_name[c->nfields], PST_MAX_NAME, "%s", names[k]);
        c->field[c->nfields++] = a;
        if (data)
            data[k] = a;
    }
    return PST_OK;
}
