// `vcu-web passwd --users FILE NAME` (auth.hpp runPasswdCommand): the password from stdin or,
// on a terminal, asked twice without echo.
#include <signal.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>
#include <string>

#include "auth.hpp"

namespace openvcu::web {
namespace {

constexpr const char* USAGE =
    "usage: vcu-web passwd --users FILE NAME\n"
    "  Adds user NAME to the users file FILE (JSON, created with mode 0600 when missing) or\n"
    "  replaces NAME's password. The password is one line read from stdin; on a terminal it is\n"
    "  asked twice without echo. The file is replaced atomically; vcu-web reads it at each login.\n"
    "  Exit status: 0 written, 1 error, 2 usage.\n";

/// The terminal's settings while echo is off, restored by the handler of a stop signal.
termios g_savedTerminal{};
volatile std::sig_atomic_t g_echoOff = 0;

extern "C" void restoreTerminalAndStop(int signalNumber) {
  if (g_echoOff != 0) ::tcsetattr(STDIN_FILENO, TCSAFLUSH, &g_savedTerminal);
  std::signal(signalNumber, SIG_DFL);
  std::raise(signalNumber);
}

/// One line of stdin without its line end; empty optional at end of input before any byte.
std::optional<std::string> readLine() {
  std::string line;
  if (!std::getline(std::cin, line) && line.empty()) return std::nullopt;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

/// Asks on the terminal with echo off; empty optional at end of input.
std::optional<std::string> askHidden(const char* prompt) {
  std::fputs(prompt, stderr);
  std::fflush(stderr);
  if (::tcgetattr(STDIN_FILENO, &g_savedTerminal) != 0) return readLine();
  termios quiet = g_savedTerminal;
  quiet.c_lflag &= ~static_cast<tcflag_t>(ECHO);
  quiet.c_lflag |= ECHONL;
  struct sigaction stop {};
  stop.sa_handler = restoreTerminalAndStop;
  struct sigaction previousInt {};
  struct sigaction previousTerm {};
  ::sigaction(SIGINT, &stop, &previousInt);
  ::sigaction(SIGTERM, &stop, &previousTerm);
  g_echoOff = 1;
  ::tcsetattr(STDIN_FILENO, TCSAFLUSH, &quiet);
  std::optional<std::string> line = readLine();
  ::tcsetattr(STDIN_FILENO, TCSAFLUSH, &g_savedTerminal);
  g_echoOff = 0;
  ::sigaction(SIGINT, &previousInt, nullptr);
  ::sigaction(SIGTERM, &previousTerm, nullptr);
  return line;
}

int fail(const std::string& message) {
  std::cerr << "vcu-web: error: " << message << '\n';
  return 1;
}

}  // namespace

int runPasswdCommand(int argc, char** argv) {
  std::optional<std::string> usersFile;
  std::optional<std::string> name;
  for (int i = 2; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--help" || argument == "-h") {
      std::cout << USAGE;
      return 0;
    }
    if (argument == "--users" && i + 1 < argc && !usersFile) {
      usersFile = argv[++i];
    } else if (argument.starts_with("--users=") && !usersFile) {
      usersFile = argument.substr(std::string_view("--users=").size());
    } else if (!argument.starts_with("-") && !name) {
      name = argument;
    } else {
      std::cerr << "vcu-web: unexpected argument '" << argument << "'\n" << USAGE;
      return 2;
    }
  }
  if (!usersFile || usersFile->empty() || !name) {
    std::cerr << USAGE;
    return 2;
  }

  std::optional<std::string> password;
  if (::isatty(STDIN_FILENO) != 0) {
    const std::string prompt = "New password for " + *name + ": ";
    password = askHidden(prompt.c_str());
    if (!password) return fail("no password given");
    const std::optional<std::string> again = askHidden("Repeat the password: ");
    if (!again || *again != *password) return fail("the passwords differ; nothing was written");
  } else {
    password = readLine();
    if (!password) return fail("no password on stdin");
  }
  if (Status written = UserFile::setPassword(*usersFile, *name, *password); !written) {
    return fail(written.error().toString());
  }
  std::cout << "vcu-web: password of '" << *name << "' written to " << *usersFile << '\n';
  return 0;
}

}  // namespace openvcu::web
