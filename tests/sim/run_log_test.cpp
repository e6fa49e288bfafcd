// The log's number formatting agrees with printf's %.6g, and summary.json
// takes observers' extra fields.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "sim_host/records/run_log.hpp"

namespace hyq::sim {
namespace {

std::string printfG6(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

std::string fast(double v) {
  std::string s;
  appendNumber(s, v);
  return s;
}

TEST(AppendNumber, MatchesPrintfOnTypicalValues) {
  for (double v : {1.0, -1.0, 0.5, 0.1, 123456.0, 999999.0, 999999.5, 1e-5, 9.999995e-5, 0.000123,
                   3.14159265, -2.718281828, 212.0634, 1e6, 1.5e7, 1e-6, -7.11158e-06, 0.9999996,
                   100.0, 10.0, 0.001, 5e-324, 1e300})
    EXPECT_EQ(fast(v), printfG6(v)) << v;
  EXPECT_EQ(fast(0.0), "0");
  EXPECT_EQ(fast(-0.0), "0");
}

// Random values over many magnitudes: identical text in all but rare
// half-way roundings, and then within one unit of the 6th digit.
TEST(AppendNumber, MatchesPrintfOnRandomValues) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> mant(-1.0, 1.0), expo(-7.0, 8.0);
  int differ = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double v = mant(rng) * std::pow(10.0, expo(rng));
    const std::string a = fast(v), b = printfG6(v);
    if (a != b) {
      ++differ;
      EXPECT_NEAR(std::stod(a), std::stod(b), 1.01e-5 * std::fabs(std::stod(b))) << a << " vs " << b;
    }
  }
  EXPECT_LT(differ, n / 1000) << differ << " of " << n << " differ";
}

TEST(Summary, WritesFieldsInOrderAsJson) {
  const auto path = std::filesystem::temp_directory_path() / "hyq_summary_test.json";
  writeSummaryJson(path.string(), {{"scenario", jsonString("a \"b\"")},
                                   {"fell", "false"},
                                   {"x", jsonNumber(0.25)},
                                   {"nan", jsonNumber(NAN)},
                                   {"extra", "{\"max\": 1}"}});
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_EQ(s.str(),
            "{\n  \"scenario\": \"a \\\"b\\\"\",\n  \"fell\": false,\n  \"x\": 0.25,\n"
            "  \"nan\": null,\n  \"extra\": {\"max\": 1}\n}\n");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace hyq::sim
