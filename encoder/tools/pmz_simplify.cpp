// pmz-simplify: placeholder until its issue lands. It says what it will do and refuses to
// pretend: every run other than --help exits 2.
#include <cstdio>
#include <cstring>

int main(int argc, char** argv) {
  if (argc > 1 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))) {
    std::puts("pmz-simplify: Simplify a mesh to a face count or ratio and write OBJ/OFF/PLY.\n(not implemented yet in this build)");
    return 0;
  }
  std::fputs("pmz-simplify: not implemented yet in this build\n", stderr);
  return 2;
}
