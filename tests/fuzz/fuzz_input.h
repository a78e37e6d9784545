/* The fuzz harnesses' inputs (tests/fuzz, docs/fuzzing.md): libFuzzer hands each harness bytes;
 * the parsers take NUL-terminated text or a file path. */
#ifndef PSTENCIL_FUZZ_INPUT_H
#define PSTENCIL_FUZZ_INPUT_H

#include <stddef.h>
#include <stdint.h>

/* A malloc'ed NUL-terminated copy of data[0..size) (free it); an embedded NUL ends the text
 * there, as it would for a file read by pst_read_text. Aborts when out of memory: a harness
 * that cannot allocate its input has found nothing. */
char *fuzz_text(const uint8_t *data, size_t size);

/* data[0..size) as an anonymous in-memory file (memfd): its path "/proc/self/fd/N" goes into
 * path (cap bytes) and the descriptor is returned, to be closed after the read. Nothing is
 * written to disk. Aborts on failure. */
int fuzz_memfile(const uint8_t *data, size_t size, char *path, size_t cap);

/* Split text at the byte `sep` into at most max pieces, in place (each `sep` becomes a NUL):
 * piece[0] is the text before the first `sep`, piece[1] the text after it up to the next, and
 * the last piece keeps any further separators. Returns the number of pieces (>= 1). */
int fuzz_split(char *text, char sep, char **piece, int max);

/* libFuzzer's entry points. Every harness defines TestOneInput (one input: it must return 0
 * and leave nothing allocated); Initialize, shared by all (fuzz_input.c), sets one OpenMP
 * thread, so each input runs the same way every time and the short runs spend the CPU on
 * inputs rather than on thread start-up. */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

#endif
