/* The cloud readers' harnesses: a cloud read must validate, a failure must say why. */
#include "fuzz_cloud_check.h"

#include <stdio.h>
#include <stdlib.h>

void fuzz_check_cloud(int status, pst_cloud *c, const char *err)
{
    if (status != PST_OK) {
        if (c || !err[0]) {
            fprintf(stderr, "status %d without a clean failure: cloud %p, message '%s'\n",
                    status, (void *)c, err);
            abort();
        }
        return;
    }
    char msg[PST_ERRLEN] = "";
    if (!c || pst_cloud_validate(c, msg) != PST_OK) {
        fprintf(stderr, "a cloud read that does not validate: %s\n", msg);
        abort();
    }
    pst_cloud_destroy(c);
}
