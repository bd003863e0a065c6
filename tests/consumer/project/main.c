/* A C program that links pmz::decoder through the installed CMake package. Until the
   format lands it checks that a non-pmz stream is refused with a message. */
#include <pmz/pmz.h>
#include <stdio.h>
#include <string.h>

int main(int argc, char** argv) {
  (void)argc;
  (void)argv;
  pmz_decoder* d = pmz_decoder_create(0, 0);
  if (!d) return 1;
  const char junk[] = "not a pmz stream";
  int rc = pmz_decoder_feed(d, junk, sizeof junk);
  int ok = rc != PMZ_OK && strlen(pmz_decoder_error(d)) > 0;
  printf("consumer: feed -> %d (%s)\n", rc, pmz_decoder_error(d));
  pmz_decoder_destroy(d);
  return ok ? 0 : 1;
}
