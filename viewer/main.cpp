// pmz-view: placeholder until the viewer issue lands. It says what it will do and refuses to
// pretend: every run other than --help exits 2.
#include <cstdio>
#include <cstring>

int main(int argc, char** argv) {
  if (argc > 1 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))) {
    std::puts("pmz-view SOURCE: stream a .pmz file, stdin or URL and show it refining\n(not implemented yet in this build)");
    return 0;
  }
  std::fputs("pmz-view: not implemented yet in this build\n", stderr);
  return 2;
}
