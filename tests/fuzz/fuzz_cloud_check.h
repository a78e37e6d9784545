/* What the cloud readers' harnesses check of every input (fuzz_cloud_check.c). */
#ifndef PSTENCIL_FUZZ_CLOUD_CHECK_H
#define PSTENCIL_FUZZ_CLOUD_CHECK_H

#include "pstencil.h"

/* The outcome of a reader: on success the cloud must pass pst_cloud_validate (a reader never
 * hands out a cloud the library would refuse); on failure there is no cloud and err holds a
 * message. Aborts otherwise, so libFuzzer records the input. Destroys c. */
void fuzz_check_cloud(int status, pst_cloud *c, const char *err);

#endif
