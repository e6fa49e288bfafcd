// The GRF problem's size is compiled once here; other sizes (tests) are
// instantiated where they are used.
#include "firmware/controller/force/qp_solver.hpp"

namespace hyq {

template class QpSolver<12, 24>;

}  // namespace hyq
