/* Joining a cloud's vector and tensor components into multi-component VTK arrays, so that
 * ParaView shows a gradient as one vector (glyphs, magnitude) and a Hessian as one symmetric
 * tensor: the convention the VTU reader undoes (docs/io.md). */
#include "vtu_groups.h"

#include "cloud_layout.h"
#include "check.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const vec_suffix[3] = {"x", "y", "z"};
/* ParaView's symmetric tensor order */
static const char *const ten_suffix[6] = {"xx", "yy", "zz", "xy", "yz", "xz"};

static int find_field(const pst_cloud *c, const char *base, size_t blen, const char *suffix)
{
    for (size_t k = 0; k < c->nfields; ++k) {
        const char *name = c->field_name[k];
        if (!strncmp(name, base, blen) && name[blen] == '_' && !strcmp(name + blen + 1, suffix))
            return (int)k;
    }
    return -1;
}

/* The group led by field k (its name ends in _x or _xx), with every required component
 * present and in no other group: 1, else 0. */
static int try_group(const pst_cloud *c, size_t k, const int *owner, pst_vtu_group *gr)
{
    const char *name = c->field_name[k];
    size_t len = strlen(name);
    int tensor = len > 3 && !strcmp(name + len - 3, "_xx");
    if (!tensor && !(len > 2 && !strcmp(name + len - 2, "_x")))
        return 0;
    size_t blen = len - (tensor ? 3 : 2);
    if ((blen == 6 && !strncmp(name, "normal", 6)) || (blen == 1 && name[0] == 'M'))
        return 0;
    memset(gr, 0, sizeof *gr);
    gr->ncomp = tensor ? 6 : 3;
    for (int m = 0; m < gr->ncomp; ++m) {
        const char *sfx = tensor ? ten_suffix[m] : vec_suffix[m];
        /* 2D: the tensor has no zz, yz, xz and the vector's z is optional */
        int needed = c->dim == 3 || (tensor ? m == 0 || m == 1 || m == 3 : m < 2);
        int f = tensor && c->dim == 2 && !needed ? -1 : find_field(c, name, blen, sfx);
        if (f >= 0 && owner[f] >= 0)
            f = -1;
        if (f < 0 && needed)
            return 0;
        gr->member[m] = f;
    }
    snprintf(gr->name, sizeof gr->name, "%.*s", (int)blen, name);
    if (tensor)
        snprintf(gr->what, sizeof gr->what, "the tensor of fields %s_xx, %s_yy, ..", gr->name,
                 gr->name);
    else
        snprintf(gr->what, sizeof gr->what, "the vector of fields %s_x, %s_y, ..", gr->name,
                 gr->name);
    return 1;
}

static void add_scalar(const pst_cloud *c, size_t k, pst_vtu_group *gr)
{
    memset(gr, 0, sizeof *gr);
    gr->ncomp = 1;
    gr->member[0] = (int)k;
    snprintf(gr->name, sizeof gr->name, "%s", c->field_name[k]);
    snprintf(gr->what, sizeof gr->what, "field '%s'", c->field_name[k]);
}

int pst_vtu_group_fields(const pst_cloud *c, pst_vtu_groups *g, char *err)
{
    size_t nf = c->nfields;
    int *owner = malloc((nf ? nf : 1) * sizeof *owner);   /* group of field k, or -1 */
    pst_vtu_group *lead = malloc((nf ? nf : 1) * sizeof *lead); /* group led by field k */
    g->group = malloc((nf ? nf : 1) * sizeof *g->group);
    g->n = 0;
    if (!owner || !lead || !g->group) {
        free(owner);
        free(lead);
        pst_vtu_groups_free(g);
        pst_set_err(err, "out of memory for the array table");
        return PST_ENOMEM;
    }
    for (size_t k = 0; k < nf; ++k)
        owner[k] = -1;
    for (size_t k = 0; k < nf; ++k) {
        if (owner[k] >= 0 || !try_group(c, k, owner, &lead[k]))
            continue;
        for (int m = 0; m < lead[k].ncomp; ++m)
            if (lead[k].member[m] >= 0)
                owner[lead[k].member[m]] = (int)k;
    }
    /* file order: each array where its first field is */
    for (size_t k = 0; k < nf; ++k) {
        if (owner[k] < 0)
            add_scalar(c, k, &g->group[g->n++]);
        else if (lead[owner[k]].ncomp > 0) {
            g->group[g->n++] = lead[owner[k]];
            lead[owner[k]].ncomp = 0; /* written */
        }
    }
    free(owner);
    free(lead);
    return PST_OK;
}

void pst_vtu_groups_free(pst_vtu_groups *g)
{
    free(g->group);
    g->group = NULL;
    g->n = 0;
}
