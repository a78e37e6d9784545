/* The VTK writers' grouping of vector and tensor fields, their refusals (two arrays of one
 * name), PolyData for .vtp, the zlib header, and the .pvd collection writer (docs/io.md). */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include "check.h"

#include <pstencil.h>

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[64];

static const char *path_of(const char *name)
{
    static char p[128];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    return p;
}

/* The whole file as text (binary bytes included), NUL-terminated; NULL when missing. */
static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *buf = calloc(1 << 20, 1);
    size_t got = buf ? fread(buf, 1, (1 << 20) - 1, f) : 0;
    fclose(f);
    (void)got;
    return buf;
}

/* A cloud of 3 particles in `dim` with fields `names`, each field k holding k + 1. */
static pst_cloud *cloud_with(int dim, const char *const *names, int n)
{
    pst_cloud *c;
    if (pst_cloud_create(&c, dim, 3, NULL) != PST_OK)
        return NULL;
    pst_cloud_set_h_uniform(c, 0.5, NULL);
    for (int i = 0; i < 3; ++i)
        pst_cloud_coord(c, 0)[i] = i;
    for (int k = 0; k < n; ++k) {
        double *f;
        CHECK_INT(pst_cloud_add_field(c, names[k], &f, NULL), PST_OK);
        for (int i = 0; i < 3; ++i)
            f[i] = k + 1;
    }
    return c;
}

static void test_groups(void)
{
    char err[PST_ERRLEN] = "";
    /* g_y before g_x: the vector sits where its first field is; u_xx.. a 2D tensor */
    static const char *const names[] = {"p", "g_y", "g_x", "u_xx", "u_yy", "u_xy", "normal_x",
                                        "normal_y", "q_x"};
    pst_cloud *c = cloud_with(2, names, 9);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("g.vtu"), NULL, err), PST_OK);
    char *t = slurp(path_of("g.vtu"));
    CHECK(t && strstr(t, "Name=\"g\" NumberOfComponents=\"3\""));
    CHECK(t && strstr(t, "Name=\"u\" NumberOfComponents=\"6\""));
    CHECK(t && !strstr(t, "Name=\"g_x\"") && !strstr(t, "Name=\"u_xx\""));
    /* normal_x, normal_y and a lone q_x stay scalars */
    CHECK(t && strstr(t, "Name=\"normal_x\" format") && strstr(t, "Name=\"q_x\" format"));
    CHECK(t && strstr(t, "Name=\"p\"") < strstr(t, "Name=\"g\"") &&
          strstr(t, "Name=\"g\"") < strstr(t, "Name=\"u\""));
    CHECK(t && strstr(t, "type=\"UnstructuredGrid\"") && !strstr(t, "compressor"));
    free(t);
    pst_cloud_destroy(c);
    /* 3D: a vector needs its z, a tensor all six */
    static const char *const names3[] = {"g_x", "g_y", "k_xx", "k_yy", "k_zz", "k_xy", "k_yz",
                                         "k_xz"};
    c = cloud_with(3, names3, 8);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("g3.vtu"), NULL, err), PST_OK);
    t = slurp(path_of("g3.vtu"));
    CHECK(t && strstr(t, "Name=\"g_x\" format"));
    CHECK(t && strstr(t, "Name=\"k\" NumberOfComponents=\"6\""));
    free(t);
    pst_cloud_destroy(c);
}

static void test_collisions(void)
{
    char err[PST_ERRLEN] = "";
    static const char *const names[] = {"u", "u_x", "u_y"};
    pst_cloud *c = cloud_with(2, names, 3);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("bad.vtu"), NULL, err), PST_EINVAL);
    CHECK(strstr(err, "bad.vtu: two PointData arrays named 'u': field 'u' and the vector of "
                      "fields u_x, u_y") != NULL);
    CHECK(access(path_of("bad.vtu"), F_OK) != 0); /* nothing written */
    pst_cloud_destroy(c);
    static const char *const v[] = {"V_x", "V_y"}; /* the cloud's own V */
    c = cloud_with(2, v, 2);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("bad.vtu"), NULL, err), PST_EINVAL);
    CHECK(strstr(err, "named 'V': one of the file's own arrays") != NULL);
    pst_cloud_destroy(c);
    static const char *const gh[] = {"w_x", "w_y", "w_xx", "w_yy", "w_xy"};
    c = cloud_with(2, gh, 5);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("bad.vtu"), NULL, err), PST_EINVAL);
    CHECK(strstr(err, "the vector of fields w_x, w_y, .. and the tensor") != NULL);
    pst_cloud_destroy(c);
}

static void test_polydata_and_zlib(void)
{
    char err[PST_ERRLEN] = "";
    static const char *const names[] = {"u"};
    pst_cloud *c = cloud_with(2, names, 1);
    CHECK_INT(pst_cloud_write_vtk(c, path_of("c.VTP"), NULL, PST_VTK_ZLIB, err), PST_OK);
    char *t = slurp(path_of("c.VTP"));
    CHECK(t && strstr(t, "<VTKFile type=\"PolyData\"") && strstr(t, "<Verts>"));
    CHECK(t && strstr(t, "NumberOfVerts=\"3\"") && !strstr(t, "Name=\"types\""));
    CHECK(t && strstr(t, "compressor=\"vtkZLibDataCompressor\""));
    /* the first array (id, 3 x 8 bytes): 1 block of 32768, a last block of 24 bytes */
    const unsigned char *p = t ? (const unsigned char *)strstr(t, "   _") + 4 : NULL;
    if (p) {
        CHECK_INT(p[0], 1);
        CHECK_INT(p[8] | p[9] << 8, 32768);
        CHECK_INT(p[16], 24);
    }
    free(t);
    pst_cloud_destroy(c);
}

static void test_pvd(void)
{
    char err[PST_ERRLEN] = "";
    pst_pvd_dataset d[2] = {{0, 0, "a_run0.vtu"}, {1.5, 2, "b&c.vtu"}};
    CHECK_INT(pst_write_pvd(path_of("s.pvd"), d, 2, err), PST_OK);
    char *t = slurp(path_of("s.pvd"));
    CHECK(t && strstr(t, "<DataSet timestep=\"0\" part=\"0\" file=\"a_run0.vtu\"/>"));
    CHECK(t && strstr(t, "<DataSet timestep=\"1.5\" part=\"2\" file=\"b&amp;c.vtu\"/>"));
    CHECK(t && strstr(t, "type=\"Collection\""));
    free(t);
    d[1].timestep = NAN;
    CHECK_INT(pst_write_pvd(path_of("n.pvd"), d, 2, err), PST_EINVAL);
    CHECK(strstr(err, "n.pvd: dataset 1 (b&c.vtu): timestep is not finite") != NULL);
    CHECK(access(path_of("n.pvd"), F_OK) != 0);
    d[1].timestep = 1;
    d[1].part = -1;
    CHECK_INT(pst_write_pvd(path_of("n.pvd"), d, 2, err), PST_EINVAL);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/pst_vtu_write_XXXXXX");
    if (!mkdtemp(dir))
        return 1;
    test_groups();
    test_collisions();
    test_polydata_and_zlib();
    test_pvd();
    const char *files[] = {"g.vtu", "g3.vtu", "c.VTP", "s.pvd"};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k)
        remove(path_of(files[k]));
    rmdir(dir);
    return check_summary("test_vtu_write");
}
