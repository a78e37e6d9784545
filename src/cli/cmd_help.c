/* `pstencil help TOPIC`: reference text generated from the program's own tables (today the
 * scene keys), so that help and docs cannot drift from what the program accepts. */
#include "cli.h"
#include "scene.h"

#include <stdio.h>
#include <string.h>

static void help_usage(FILE *f)
{
    fputs("usage: pstencil help scene [--markdown]\n\n"
          "  scene        every key of a scene file: type, default, units, allowed values\n"
          "  --markdown   print it as docs/scenes.md (with an example scene)\n",
          f);
}

int cli_help(const cli_ctx *ctx, int argc, char **argv)
{
    (void)ctx; /* help is the result itself: --quiet changes nothing */
    if (argc >= 1 && (strcmp(argv[0], "--help") == 0 || strcmp(argv[0], "-h") == 0)) {
        help_usage(stdout);
        return CLI_OK;
    }
    if (argc < 1 || strcmp(argv[0], "scene") != 0) {
        if (argc >= 1)
            fprintf(stderr, "pstencil: help: unknown topic '%s'\n", argv[0]);
        help_usage(stderr);
        return CLI_USAGE;
    }
    int markdown = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--markdown") == 0) {
            markdown = 1;
        } else {
            fprintf(stderr, "pstencil: help scene: unknown option '%s'\n", argv[i]);
            help_usage(stderr);
            return CLI_USAGE;
        }
    }
    pst_scene_print_help(stdout, markdown);
    return fflush(stdout) == 0 ? CLI_OK : CLI_BAD_INPUT;
}
