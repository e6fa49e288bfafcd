// The documented range of every tuning number (params.hpp): each field's
// own in param_table.hpp, and the rules that compare two fields.
// Controller::init refuses parameters outside them; the scenario reader
// reports the key that broke them. Ranges keep every array index in bounds
// (sample windows, iteration counts), every divisor away from 0, every time
// constant at least one tick and every gain physically meaningful.
#pragma once
#include "firmware/controller/params.hpp"

namespace hyq {

struct ParamIssue {
  const char* name = "";   // e.g. "gait.duty_factor"
  const char* rule = "";   // e.g. "in [0.5, 0.99]"
};

// True when every parameter is finite and within its range, each bool's byte
// 0 or 1, and the rules between fields hold; else false with the first
// field (in param_table.hpp's order), then the first rule, that does not.
bool checkParams(const Params& params, ParamIssue& issue);

}  // namespace hyq
