// The documented range of every tuning number (params.hpp), in one place.
// Controller::init refuses parameters outside them; the scenario reader
// reports the key that broke them. Ranges keep every array index in bounds
// (sample windows, iteration counts) and every gain physically meaningful.
#pragma once
#include "firmware/controller/params.hpp"

namespace hyq {

struct ParamIssue {
  const char* name = "";   // e.g. "gait.duty_factor"
  const char* rule = "";   // e.g. "in [0.5, 0.99]"
};

// True when every parameter is finite and within its range; else false with
// the first one that is not.
bool checkParams(const Params& params, ParamIssue& issue);

}  // namespace hyq
