/* The fields of a VTU file: a PointData array of no other role is one field (1 component), a
 * vector NAME_x, NAME_y[, NAME_z] (3 components) or ParaView's symmetric tensor NAME_xx, ...
 * (6 components, stored XX, YY, ZZ, XY, YZ, XZ). In 2D the components out of the plane are
 * dropped and must be 0, so that nothing in the file is lost silently. */
#include "vtu_read.h"

#include <stdlib.h>
#include <string.h>

static const char *const vec_names[3] = {"x", "y", "z"};
static const char *const ten_names[6] = {"xx", "yy", "zz", "xy", "yz", "xz"};

int vtu_field_parts(int ncomp, int dim, int comp[6])
{
    static const int vec[3] = {0, 1, 2}, ten3[6] = {0, 1, 2, 3, 4, 5}, ten2[3] = {0, 1, 3};
    if (ncomp == 1) {
        comp[0] = 0;
        return 1;
    }
    const int *src = ncomp == 3 ? vec : dim == 3 ? ten3 : ten2;
    int n = ncomp == 3 ? dim : dim == 3 ? 6 : 3;
    memcpy(comp, src, (size_t)n * sizeof *comp);
    return n;
}

/* The name of component `comp` of an array of ncomp components ("" for a scalar). */
static const char *comp_name(int ncomp, int comp)
{
    return ncomp == 1 ? "" : ncomp == 3 ? vec_names[comp] : ten_names[comp];
}

/* One field name NAME or NAME_SUFFIX of array a, checked. */
static int field_name(reader *r, const vtu_in_array *a, int comp, char *out)
{
    const char *suffix = comp_name(a->ncomp, comp);
    int len = snprintf(out, PST_MAX_NAME, "%s%s%s", a->name, *suffix ? "_" : "", suffix);
    if (len < PST_MAX_NAME && pst_is_identifier(out) && !pst_is_reserved_column(out))
        return PST_OK;
    if (*suffix)
        return vtu_fail_at(r, a->at,
                           "PointData array '%.64s' cannot be a field: its component field "
                           "'%.64s_%s' must be a C identifier shorter than %d characters",
                           a->name, a->name, suffix, PST_MAX_NAME);
    return vtu_fail_at(r, a->at,
                       "PointData array '%.64s' cannot be a field: field names are C "
                       "identifiers shorter than %d characters and not one of x, y, z, nx, "
                       "ny, nz, mx, my, mz",
                       a->name, PST_MAX_NAME);
}

int vtu_field_names(reader *r, int dim, vtu_in_array *const *arrays, size_t na,
                    char (**names)[PST_MAX_NAME], size_t *count)
{
    size_t n = 0, cap = 0;
    char(*nm)[PST_MAX_NAME] = NULL;
    int st = PST_OK;
    const vtu_in_array **owner = NULL; /* the array of each field, for the messages */
    for (size_t k = 0; k < na && st == PST_OK; ++k) {
        int comp[6], np = vtu_field_parts(arrays[k]->ncomp, dim, comp);
        if (n + (size_t)np > PST_MAX_FIELDS) {
            st = vtu_fail_at(r, arrays[k]->at, "PointData array '%.64s': more than the %d "
                             "fields a cloud file may have", arrays[k]->name, PST_MAX_FIELDS);
            break;
        }
        if (n + (size_t)np > cap) {
            cap = cap ? 2 * cap : 64;
            void *a = realloc(nm, cap * sizeof *nm), *b = realloc(owner, cap * sizeof *owner);
            nm = a ? a : nm;
            owner = b ? b : owner;
            if (!a || !b) {
                st = vtu_oom(r);
                break;
            }
        }
        for (int j = 0; j < np && st == PST_OK; ++j) {
            owner[n] = arrays[k];
            st = field_name(r, arrays[k], comp[j], nm[n++]);
        }
    }
    const char **list = st == PST_OK ? malloc((n ? n : 1) * sizeof *list) : NULL;
    if (st == PST_OK && !list)
        st = vtu_oom(r);
    size_t first = 0, again = 0;
    for (size_t k = 0; list && k < n; ++k)
        list[k] = nm[k];
    int found = list ? pst_find_repeated_name(list, n, &first, &again) : 0;
    free(list);
    if (st == PST_OK && found < 0)
        st = vtu_oom(r);
    if (st == PST_OK && found > 0)
        st = vtu_fail_at(r, owner[again]->at, "two PointData arrays give the field '%s'",
                         nm[again]);
    free(owner);
    if (st != PST_OK) {
        free(nm);
        return st;
    }
    *names = nm;
    *count = n;
    return PST_OK;
}

int vtu_store_field(reader *r, pst_cloud *c, const vtu_in_array *a, const double *v,
                    const size_t *part, size_t field)
{
    int comp[6], np = vtu_field_parts(a->ncomp, c->dim, comp), keep[6] = {0};
    for (int j = 0; j < np; ++j)
        keep[comp[j]] = 1;
    size_t nc = (size_t)a->ncomp;
    for (size_t k = 0; k < c->n; ++k) {
        for (size_t j = 0; j < nc; ++j)
            if (!keep[j] && v[nc * k + j] != 0)
                return vtu_fail(r,
                                "array '%.64s', point %zu: component %s = %.17g must be 0 in "
                                "a 2D cloud (every z is 0)",
                                a->name, k, comp_name(a->ncomp, (int)j), v[nc * k + j]);
        for (int j = 0; j < np; ++j)
            c->field[field + (size_t)j][part[k]] = v[nc * k + (size_t)comp[j]];
    }
    return PST_OK;
}
