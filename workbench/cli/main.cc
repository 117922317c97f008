#include <cstdio>
#include <cstring>
int main(int argc, char** argv) {
  std::puts("csw: the Cued Speech Workbench");
  return argc > 1 && std::strcmp(argv[1], "--help") != 0 ? 1 : 0;
}
