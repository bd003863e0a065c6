// pmz-decode: placeholder until the format issue lands. It says what it will do and refuses to
// pretend: every run other than --help exits 2.
#include <cstdio>
#include <cstring>

int main(int argc, char** argv) {
  if (argc > 1 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))) {
    std::puts("pmz-decode: Decode a .pmz stream (or its first N bytes) to OBJ/PLY/OFF at a chosen level of detail.\n(not implemented yet in this build)");
    return 0;
  }
  std::fputs("pmz-decode: not implemented yet in this build\n", stderr);
  return 2;
}
