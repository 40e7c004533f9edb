// The main of every test executable: doctest's, plus one guard. ctest runs each discovered
// case by name (--test-case=NAME); a case whose name CMake cut short (a ';' in the name
// splits a CMake list) would match nothing and "pass" without running. Here a run with a
// test-case filter that selects no case fails instead, and a run that failed nothing but
// skipped cases (tests/skip.hpp) exits with 77, which ctest reports as "Skipped".
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstring>
#include <iostream>

#include "skip.hpp"

namespace {

unsigned g_selected = 0;

struct SelectionListener : doctest::IReporter {
  explicit SelectionListener(const doctest::ContextOptions& /*options*/) {}
  void report_query(const doctest::QueryData&) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats& stats) override { g_selected = stats.numTestCasesPassingFilters; }
  void test_case_start(const doctest::TestCaseData&) override {}
  void test_case_reenter(const doctest::TestCaseData&) override {}
  void test_case_end(const doctest::CurrentTestCaseStats&) override {}
  void test_case_exception(const doctest::TestCaseException&) override {}
  void subcase_start(const doctest::SubcaseSignature&) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData&) override {}
  void log_message(const doctest::MessageData&) override {}
  void test_case_skipped(const doctest::TestCaseData&) override {}
};

}  // namespace

REGISTER_LISTENER("openvcu-selection", 1, SelectionListener);

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int result = context.run();
  if (context.shouldExit()) return result;
  bool filtered = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--test-case=", 12) == 0 || std::strncmp(argv[i], "-tc=", 4) == 0) filtered = true;
  }
  if (filtered && g_selected == 0) {
    std::cerr << "error: no test case matches the --test-case filter (is the name cut at a ';'?)\n";
    return 1;
  }
  if (result == 0 && openvcu::testing::skippedCases() > 0) {
    std::cerr << openvcu::testing::skippedCases() << " test case(s) skipped, not run\n";
    return openvcu::testing::SKIPPED_EXIT_CODE;
  }
  return result;
}
