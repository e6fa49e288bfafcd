// hyq_golden: regenerates the golden replay's files (tests/golden/).
//   hyq_golden reference   replay the stored trace, rewrite reference.csv
//   hyq_golden record      record a new trace from the simulator, then the reference
// A new reference is for an intended change of behaviour: its commit says why.
#include <cstdio>
#include <cstring>
#include <string>

#include "tests/golden/golden.hpp"

int main(int argc, char** argv) {
  using namespace hyq::golden;
  const bool record = argc == 2 && std::strcmp(argv[1], "record") == 0;
  if (!(argc == 2 && (record || std::strcmp(argv[1], "reference") == 0))) {
    std::fprintf(stderr, "usage: hyq_golden reference|record\n");
    return 2;
  }
  const std::string dir = std::string(HYQ_SOURCE_DIR) + "/tests/golden/";
  std::string error;
  if (record && !writeTrace(dir + "trace.bin", recordTrace(), error)) {
    std::fprintf(stderr, "hyq_golden: %s\n", error.c_str());
    return 1;
  }
  const auto trace = readTrace(dir + "trace.bin", error);
  if (trace.empty() || !writeReference(dir + "reference.csv", replay(trace, goldenParams()), error)) {
    std::fprintf(stderr, "hyq_golden: %s\n", error.c_str());
    return 1;
  }
  std::printf("hyq_golden: %zu ticks replayed; %sreference.csv written\n", trace.size(),
              record ? "trace.bin and " : "");
  return 0;
}
