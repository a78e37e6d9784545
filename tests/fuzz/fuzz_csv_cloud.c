/* libFuzzer harness of the CSV cloud reader (pst_cloud_read_csv, docs/io.md): any bytes as a
 * cloud file, read from memory. */
#include "fuzz_cloud_check.h"
#include "fuzz_input.h"

#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64], err[PST_ERRLEN] = "";
    int fd = fuzz_memfile(data, size, path, sizeof path);
    pst_cloud *c = NULL;
    int st = pst_cloud_read_csv(&c, path, err);
    close(fd);
    fuzz_check_cloud(st, c, err);
    return 0;
}
