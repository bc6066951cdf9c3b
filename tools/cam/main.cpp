// picksight-cam entry point: everything but the process boundary lives in
// the picksight_camcli library, where the tests can reach it.
#include <iostream>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "cam_cli.hpp"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  zmq::context_t context;
  return picksight::cam::runCamCli(args, std::cout, std::cerr, context);
}
