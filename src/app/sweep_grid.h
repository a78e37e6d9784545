/* A sweep's combinations as scenes (src/app/sweep_grid.c). Private to the sweep files. */
#ifndef PSTENCIL_SWEEP_GRID_H
#define PSTENCIL_SWEEP_GRID_H

#include "scene.h"
#include "sweep.h"

#include <stdint.h>

/* "key=value key=value" of combination k, for messages. */
void sweep_combo_label(const pst_sweep *sw, size_t k, char *buf, size_t len);

/* The VTU path of run k when the sweep writes a .pvd: "STEM_runK.vtu" beside it, with STEM the
 * .pvd path without its extension; `base` (may be NULL) receives the name relative to the
 * .pvd's folder, as the collection lists it. */
void sweep_run_vtu(const pst_sweep *sw, size_t k, char *path, size_t len, const char **base);

/* The scene of combination k: the sweep's scene text with outputs off, the fixed overrides,
 * then the combination's values. PST_ENOMEM when the overrides cannot be built; otherwise
 * pst_scene_parse's status, with its message in msg. */
int sweep_combo_scene(const pst_sweep *sw, size_t k, pst_scene *s, char *msg, size_t msglen);

/* A 64-bit FNV-1a digest of what defines the sweep's runs (scene text and path, keys, values,
 * overrides, outputs): a worker checks that it read the sweep its parent did. */
uint64_t sweep_digest(const pst_sweep *sw);

#endif
