// Catch2's main, compiled once for every test executable.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "picksight/common/large_buffers.hpp"

int main(int argc, char* argv[]) {
  // The allocator as the services and the offline commands set it: without
  // it every frame-sized image is mapped afresh and its pages faulted in,
  // which cost the vision tests more than half their time (a front-light
  // test binary 15 s instead of 6, two thirds of it in the kernel).
  picksight::retainLargeBuffers();
  Catch::Session session;
  // A test spec that matches nothing is an error, not a pass: CTest runs one
  // test case per entry by name, and a name CTest mangled must fail loudly.
  // Set before parsing so that --warn on the command line adds to it.
  session.configData().warnings = Catch::WarnAbout::NoTests;
  const int parsed = session.applyCommandLine(argc, argv);
  if (parsed != 0) return parsed;
  return session.run();
}
