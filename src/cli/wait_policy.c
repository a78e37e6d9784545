/* The program's OpenMP wait policy (docs/cli.md, "Threads on shared cores"): passive unless the
 * user chose one. libgomp reads OMP_WAIT_POLICY once, when it is loaded, before main runs, so
 * setting the variable in main would change nothing: the program instead executes itself again
 * (same process, argv, stdin, exit code; ignored signals stay ignored) with the variable set,
 * and a marker variable that stops a second re-exec and tells sysinfo the policy is ours. */
#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv */

#include "cli.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Set only in the re-executed program; removed at once so that nothing it runs inherits it. */
#define MARKER "PSTENCIL_WAIT_POLICY_SET"

static char policy[64] = "libgomp's default (OMP_WAIT_POLICY unset, re-exec failed)";

void cli_default_wait_policy(char **argv)
{
    const char *user = getenv("OMP_WAIT_POLICY");
    if (getenv(MARKER)) {
        unsetenv(MARKER);
        if (user && strcmp(user, "PASSIVE") == 0) {
            snprintf(policy, sizeof policy, "passive (default)");
            return;
        }
        /* the marker came from elsewhere with another policy: the user's */
    } else if (!user) {
        if (setenv("OMP_WAIT_POLICY", "PASSIVE", 1) == 0 && setenv(MARKER, "1", 1) == 0) {
            fflush(NULL);
            execv("/proc/self/exe", argv);
        }
        /* no /proc (or no memory for the environment): run on under libgomp's default */
        unsetenv("OMP_WAIT_POLICY");
        unsetenv(MARKER);
        return;
    }
    size_t n = 0;
    for (; user[n] && n < 20; ++n)
        policy[n] = (char)tolower((unsigned char)user[n]);
    snprintf(policy + n, sizeof policy - n, " (OMP_WAIT_POLICY)");
}

const char *cli_wait_policy(void)
{
    return policy;
}
