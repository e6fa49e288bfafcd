// hyq_golden: regenerates the golden replays' files (tests/golden/<case>/).
//   hyq_golden reference [CASE]   replay the stored trace, rewrite reference.csv
//   hyq_golden record [CASE]      record a new trace from the simulator, then the reference
// Without CASE, every case (crawl, trot, switch). A new reference is for an
// intended change of behaviour: its commit says why.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "tests/golden/golden.hpp"

int main(int argc, char** argv) {
  using namespace hyq::golden;
  const bool record = argc >= 2 && std::strcmp(argv[1], "record") == 0;
  if (argc < 2 || argc > 3 || !(record || std::strcmp(argv[1], "reference") == 0)) {
    std::fprintf(stderr, "usage: hyq_golden reference|record [crawl|trot|switch]\n");
    return 2;
  }
  std::vector<const Case*> which;
  if (argc == 3) {
    const Case* c = findCase(argv[2]);
    if (!c) {
      std::fprintf(stderr, "hyq_golden: no golden case '%s' (crawl, trot, switch)\n", argv[2]);
      return 2;
    }
    which.push_back(c);
  } else {
    for (const Case& c : cases()) which.push_back(&c);
  }
  for (const Case* c : which) {
    const std::string dir = caseDir(*c);
    std::string error;
    if (record && !writeTrace(dir + "trace.bin", recordTrace(*c), error)) {
      std::fprintf(stderr, "hyq_golden: %s\n", error.c_str());
      return 1;
    }
    const auto trace = readTrace(dir + "trace.bin", error);
    if (trace.empty() || !writeReference(dir + "reference.csv", replay(trace, goldenParams(*c)), error)) {
      std::fprintf(stderr, "hyq_golden: %s\n", error.c_str());
      return 1;
    }
    std::printf("hyq_golden %s: %zu ticks replayed; %sreference.csv written\n", c->name, trace.size(),
                record ? "trace.bin and " : "");
  }
  return 0;
}
