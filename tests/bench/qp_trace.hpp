// The QP trace: every tick's GRF problem of a simulator run with the
// solution the solver gave it (qp_record writes it, qp_replay reads it).
//
// File layout (host byte order, doubles as IEEE 754 binary64):
//   header  QpTraceHeader
//   records QpTraceRecord, one per tick whose problem the controller solved
// Matrices are stored column-major, as Eigen holds them.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "firmware/controller/force/grf_qp.hpp"

namespace hyq::bench {

constexpr char kQpTraceMagic[8] = {'H', 'Y', 'Q', 'Q', 'P', 'T', 'R', '1'};

struct QpTraceHeader {
  char magic[8];
  int32_t variables;        // [-] kGrfVariables
  int32_t inequalities;     // [-] kGrfConstraints
  int32_t max_iterations;   // [-] QpParams of the run
  int32_t recovery;         // [-] 1: slip recovery on
  double feasibility_tolerance;  // [N]
  double pyramid_scale;     // [-] RecoveryParams of the run
  uint64_t seed;            // [-] sensor noise seed
  char scenario[64];        // scenario name, NUL-terminated
};

struct QpTraceRecord {
  uint64_t tick;            // [-] sensor frame tick
  double hessian[kGrfVariables * kGrfVariables];
  double gradient[kGrfVariables];
  double ineq_matrix[kGrfConstraints * kGrfVariables];
  double ineq_bound[kGrfConstraints];
  double x[kGrfVariables];  // [N] the solver's solution when recorded
  int32_t status;           // QpStatus when recorded
  int32_t iterations;       // [-] active-set changes when recorded
  int32_t active;           // [-] active inequalities at the solution when recorded
  int32_t reserved;
};

inline void toRecord(const GrfProblem& p, QpTraceRecord& r) {
  std::memcpy(r.hessian, p.hessian.data(), sizeof r.hessian);
  std::memcpy(r.gradient, p.gradient.data(), sizeof r.gradient);
  std::memcpy(r.ineq_matrix, p.ineq_matrix.data(), sizeof r.ineq_matrix);
  std::memcpy(r.ineq_bound, p.ineq_bound.data(), sizeof r.ineq_bound);
}

inline void fromRecord(const QpTraceRecord& r, GrfProblem& p) {
  std::memcpy(p.hessian.data(), r.hessian, sizeof r.hessian);
  std::memcpy(p.gradient.data(), r.gradient, sizeof r.gradient);
  std::memcpy(p.ineq_matrix.data(), r.ineq_matrix, sizeof r.ineq_matrix);
  std::memcpy(p.ineq_bound.data(), r.ineq_bound, sizeof r.ineq_bound);
}

// Reads a whole trace; false with `error` set on a missing, short or foreign file.
inline bool readQpTrace(const std::string& path, QpTraceHeader& header,
                        std::vector<QpTraceRecord>& records, std::string& error) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    error = path + ": cannot open";
    return false;
  }
  bool ok = std::fread(&header, sizeof header, 1, f) == 1 &&
            std::memcmp(header.magic, kQpTraceMagic, sizeof kQpTraceMagic) == 0 &&
            header.variables == kGrfVariables && header.inequalities == kGrfConstraints;
  if (!ok) {
    error = path + ": not a QP trace of this problem size";
  } else {
    records.clear();
    QpTraceRecord r;
    while (std::fread(&r, sizeof r, 1, f) == 1) records.push_back(r);
    if (!std::feof(f)) {
      error = path + ": read error";
      ok = false;
    }
  }
  std::fclose(f);
  header.scenario[sizeof header.scenario - 1] = '\0';
  return ok;
}

}  // namespace hyq::bench
