#include "firmware/controller/param_table.hpp"

#include <cmath>
#include <cstring>

namespace hyq {
namespace {

// Element k of field f, from the bytes of a Params: a bool or the gait kind
// as its byte, so that any byte reads as a number.
double elementValue(const uint8_t* bytes, const ParamField& f, int k) {
  const uint8_t* at = bytes + f.offset + static_cast<size_t>(k) * paramElementSize(f.type);
  if (f.type == ParamType::kDouble) {
    double value;
    std::memcpy(&value, at, sizeof value);
    return value;
  }
  if (f.type == ParamType::kInt) {
    int value;
    std::memcpy(&value, at, sizeof value);
    return static_cast<double>(value);
  }
  uint8_t byte;
  std::memcpy(&byte, at, sizeof byte);
  return static_cast<double>(byte);
}

bool inRange(const ParamField& f, double value) {
  if (!std::isfinite(value) || value > f.hi) return false;
  if ((f.flags & kParamOpenLow) != 0 ? !(value > f.lo) : !(value >= f.lo)) return false;
  return !(value > 0.0 && value < f.on_min);
}

bool fail(ParamIssue& issue, const char* name, const char* rule) {
  issue.name = name;
  issue.rule = rule;
  return false;
}

}  // namespace

bool checkParamFields(const uint8_t* bytes, ParamIssue& issue) {
  double dt;  // [s] one tick; checked as the table's first field
  std::memcpy(&dt, bytes + offsetof(Params, dt), sizeof dt);
  for (const ParamField& f : kParamFields) {
    for (int k = 0; k < f.count; ++k) {
      const double value = elementValue(bytes, f, k);
      if (!inRange(f, value)) return fail(issue, f.name, f.rule);
      if ((f.flags & kParamAtLeastTick) != 0 && value != 0.0 && !(value >= dt))
        return fail(issue, f.name, f.lo <= 0.0 ? kZeroOrTickRule : kTickRule);
    }
  }
  return true;
}

bool checkBoolBytes(const uint8_t* bytes, ParamIssue& issue) {
  for (const ParamField& f : kParamFields) {
    if (f.type != ParamType::kBool) continue;
    for (int k = 0; k < f.count; ++k)
      if (!inRange(f, elementValue(bytes, f, k))) return fail(issue, f.name, f.rule);
  }
  return true;
}

}  // namespace hyq
