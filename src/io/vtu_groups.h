/* Which of a cloud's fields the VTK writer joins into one multi-component array (docs/io.md,
 * "Vectors and tensors"). Private to io/. */
#ifndef PSTENCIL_VTU_GROUPS_H
#define PSTENCIL_VTU_GROUPS_H

#include "pstencil/cloud.h"

#include <stddef.h>

enum { PST_VTU_MAX_COMP = 6 };

/* One PointData array made of fields: member[m] is the field index of component m, -1 for a
 * component written as 0; `what` says which fields it is made of, for messages. */
typedef struct {
    char name[PST_MAX_NAME];
    int ncomp;
    int member[PST_VTU_MAX_COMP];
    char what[4 * PST_MAX_NAME + 48];
} pst_vtu_group;

typedef struct {
    pst_vtu_group *group;
    size_t n;
} pst_vtu_groups;

/* The arrays of c's fields in file order (each at the place of its first field): NAME_x,
 * NAME_y (and NAME_z: required in 3D, taken when present in 2D) as one 3-component array
 * NAME; NAME_xx, NAME_yy, NAME_xy (2D) or the six of 3D as one 6-component array NAME in the
 * order XX, YY, ZZ, XY, YZ, XZ; NAME "normal" or "M" never groups; every other field a
 * 1-component array. PST_OK or PST_ENOMEM (message in err). Free with pst_vtu_groups_free. */
int pst_vtu_group_fields(const pst_cloud *c, pst_vtu_groups *g, char *err);
void pst_vtu_groups_free(pst_vtu_groups *g);

#endif
