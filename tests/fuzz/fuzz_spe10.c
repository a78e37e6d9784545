/* libFuzzer harness of the SPE10 permeability reader (pst_spe10_read, docs/spe10.md): any bytes
 * as the RTSPHEM Tarbert file and as each of the three GEOS files. The reader picks the format
 * by the file name, so the input lives in one in-memory file (memfd) that four symbolic links
 * in a temporary folder name: perm.txt, permx.geos, permy.geos and permz.geos (removed at
 * exit). The sub-block and the GEOS layer follow from the input's size, so that the committed
 * seeds stay the real files. A grid read must hold finite values > 0 in a sub-block of the
 * layer; a failure must have a message and leave the grid empty. */
#define _GNU_SOURCE /* memfd_create, mkdtemp */

#include "fuzz_input.h"
#include "pstencil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

static const char *const names[4] = {"perm.txt", "permx.geos", "permy.geos", "permz.geos"};
static char dir[64];
static int fd = -1;

static void remove_links(void)
{
    char p[128];
    for (int k = 0; k < 4; ++k) {
        snprintf(p, sizeof p, "%s/%s", dir, names[k]);
        unlink(p);
    }
    rmdir(dir);
}

/* The memfd and its four names, once per process. */
static void setup(void)
{
    fd = memfd_create("fuzz-spe10", MFD_CLOEXEC);
    snprintf(dir, sizeof dir, "/tmp/pst_fuzz_spe10.XXXXXX");
    if (fd < 0 || !mkdtemp(dir)) {
        perror("fuzz_spe10 setup");
        abort();
    }
    char target[64], p[128];
    snprintf(target, sizeof target, "/proc/self/fd/%d", fd);
    for (int k = 0; k < 4; ++k) {
        snprintf(p, sizeof p, "%s/%s", dir, names[k]);
        if (symlink(target, p) != 0) {
            perror("fuzz_spe10 symlink");
            abort();
        }
    }
    atexit(remove_links);
}

static void check(int st, const pst_perm_grid *g, int ni, int nj, const char *err)
{
    if (st != PST_OK) {
        if (!err[0] || g->k[0] || g->nx) {
            fprintf(stderr, "spe10: status %d without a message or with a grid left\n", st);
            abort();
        }
        return;
    }
    if (g->nx != ni || g->ny != nj || g->nz != 1) {
        fprintf(stderr, "spe10: a %dx%dx%d grid for a %dx%d block\n", g->nx, g->ny, g->nz, ni, nj);
        abort();
    }
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < (size_t)ni * (size_t)nj; ++i)
            if (!(isfinite(g->k[c][i]) && g->k[c][i] > 0)) {
                fprintf(stderr, "spe10: value %g kept\n", g->k[c][i]);
                abort();
            }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (fd < 0)
        setup();
    if (ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != (ssize_t)size) {
        perror("fuzz_spe10 write");
        abort();
    }
    /* a sub-block of the 60 x 220 layer, and for one size in 17 one that reaches past it */
    int i0 = (int)(size % 60), j0 = (int)(size / 60 % 220);
    int ni = 1 + (int)(size / 7 % (size_t)(60 - i0));
    int nj = 1 + (int)(size / 13 % (size_t)(220 - j0));
    if (size % 17 == 0)
        ni += 60 - i0;
    char path[128];
    for (int k = 0; k < 2; ++k) {
        pst_perm_grid g;
        char err[PST_ERRLEN] = "";
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        int layer = k == 0 ? 0 : 84 + (int)(size & 1);
        int st = pst_spe10_read(&g, path, layer, i0, j0, ni, nj, err);
        check(st, &g, ni, nj, err);
        pst_perm_grid_free(&g);
    }
    return 0;
}
