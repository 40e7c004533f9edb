// vcu: the openvcu command-line tool. The command tree and every command live in the
// vcu_cli library (src/); main only connects it to the process's stdout and stderr.
// `vcu --help` is the manual; README.md has the overview.

#include <cstdio>

#include "cli.hpp"
#include "sink.hpp"

int main(int argc, char** argv) {
  openvcu::cli::FileSink out(stdout);
  openvcu::cli::FileSink err(stderr);
  return openvcu::cli::run(argc, argv, openvcu::cli::Streams{out, err});
}
