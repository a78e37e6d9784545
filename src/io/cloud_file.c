/* A cloud file read by the reader its extension names: the one rule of the command line and of
 * the scenes' cloud.file (docs/io.md, "Which reader"). */
#include "check.h"

#include <string.h>
#include <strings.h>

int pst_cloud_read(pst_cloud **out, const char *path, char *err)
{
    PST_CHECK(!out || !path, PST_EINVAL, err, "read: cloud and path must not be NULL");
    *out = NULL;
    const char *ext = strrchr(path, '.');
    if (ext && strchr(ext, '/'))
        ext = NULL; /* a dot in a folder's name, not an extension */
    if (ext && (strcasecmp(ext, ".vtu") == 0 || strcasecmp(ext, ".vtp") == 0))
        return pst_cloud_read_vtu(out, path, err);
    PST_CHECK(!ext || strcasecmp(ext, ".csv") != 0, PST_EINPUT, err,
              "%s: unknown extension (a cloud file is .csv, .vtu or .vtp)", path);
    return pst_cloud_read_csv(out, path, err);
}
