/* The scheme registry: the table of every scheme (operator.h) and the queries by name that
 * planning needs before an operator exists. */
#include "operator.h"

#include <string.h>

/* One entry per line; the order is the order of listings. */
static const pst_scheme *const registry[] = {
    &pst_scheme_brookshaw,
    &pst_scheme_cb,
    &pst_scheme_schwaiger,
    &pst_scheme_lv,
    &pst_scheme_cspm,
    &pst_scheme_icspm,
    &pst_scheme_csph2g,
    &pst_scheme_mixed0,
    &pst_scheme_mixed1,
    &pst_scheme_mixed2,
    &pst_scheme_qsfdi,
    &pst_scheme_lsmps,
    &pst_scheme_lpmps,
};
#define NSCHEMES ((int)(sizeof registry / sizeof *registry))

int pst_scheme_count(void) { return NSCHEMES; }
const char *pst_scheme_name(int i) { return i >= 0 && i < NSCHEMES ? registry[i]->name : NULL; }
const char *pst_scheme_description(int i)
{
    return i >= 0 && i < NSCHEMES ? registry[i]->description : NULL;
}

const pst_scheme *pst_scheme_find(const char *name)
{
    for (int i = 0; i < NSCHEMES && name; ++i)
        if (strcmp(registry[i]->name, name) == 0)
            return registry[i];
    return NULL;
}

/* CG's symmetric scaling (docs/schemes/cb.md, "Symmetry") exists for these two schemes only. */
int pst_scheme_symmetrisable(const pst_scheme *s)
{
    return s == &pst_scheme_brookshaw || s == &pst_scheme_cb;
}

int pst_scheme_supports(const char *name, int what)
{
    const pst_scheme *s = pst_scheme_find(name);
    if (!s)
        return 0;
    switch (what) {
    case PST_SUPPORTS_GRADIENT: return s->gradient != NULL;
    case PST_SUPPORTS_HESSIAN: return s->hessian != NULL;
    case PST_SUPPORTS_INTERPOLATE: return s->interpolate != NULL;
    case PST_SUPPORTS_MOBILITY: return s->mobility;
    case PST_SUPPORTS_SYMMETRIC: return pst_scheme_symmetrisable(s);
    case PST_SUPPORTS_DERIVATIVES_ONLY: return s->derivatives_standalone;
    case PST_SUPPORTS_HALF_LIST: return s->half_rows != NULL;
    case PST_SUPPORTS_KEEP: return s->keep_bytes[1][0] > 0;
    default: return 0;
    }
}

int pst_scheme_halo(const char *name)
{
    const pst_scheme *s = pst_scheme_find(name);
    return !s ? 0 : s->halo > 1 ? s->halo : 1;
}

pst_kernel pst_scheme_default_kernel(const char *name)
{
    const pst_scheme *s = pst_scheme_find(name);
    return s ? s->default_kernel : PST_KERNEL_UNKNOWN;
}

const char *pst_scheme_fallback(const char *name)
{
    const pst_scheme *s = pst_scheme_find(name);
    return s ? s->fallback : NULL;
}

int pst_scheme_degree(const char *name, int lattice)
{
    const pst_scheme *s = pst_scheme_find(name);
    return !s ? -1 : lattice ? s->degree_lattice : s->degree;
}

int pst_scheme_variants(const char *name)
{
    const pst_scheme *s = pst_scheme_find(name);
    return !s ? 0 : s->variants > 1 ? s->variants : 1;
}

int pst_scheme_data_bytes(const char *name, int dim)
{
    const pst_scheme *s = pst_scheme_find(name);
    return s && (dim == 2 || dim == 3) ? s->data_bytes[dim - 2] : 0;
}

int pst_scheme_apply_bytes(const char *name)
{
    const pst_scheme *s = pst_scheme_find(name);
    return s && s->lanes ? 4 * (int)sizeof(double) : 0;
}

int pst_scheme_keep_bytes(const char *name, int dim, int keep)
{
    const pst_scheme *s = pst_scheme_find(name);
    if (!s || (dim != 2 && dim != 3))
        return 0;
    return (keep & PST_KEEP_GRADIENT ? s->keep_bytes[dim - 2][0] : 0) +
           (keep & PST_KEEP_HESSIAN ? s->keep_bytes[dim - 2][1] : 0);
}

int pst_scheme_amg_own(const char *name)
{
    const pst_scheme *s = pst_scheme_find(name);
    return s ? s->amg_own : 0;
}

/* The proxy radius of the schemes that name none: the whole list's iterations at a quarter
 * (2D) to a sixth (3D) of its entries for lpmps and lv (docs/solving.md). */
#define AMG_RADIUS_DEFAULT 1.6

double pst_scheme_amg_radius(const char *name)
{
    const pst_scheme *s = pst_scheme_find(name);
    return !s ? 0 : s->amg_radius > 0 ? s->amg_radius : AMG_RADIUS_DEFAULT;
}

const char *pst_scheme_names(char *names, size_t size)
{
    names[0] = '\0';
    for (int i = 0; i < NSCHEMES; ++i) {
        strncat(names, i ? ", " : "", size - strlen(names) - 1);
        strncat(names, registry[i]->name, size - strlen(names) - 1);
    }
    return names;
}
