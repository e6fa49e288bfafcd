#include "firmware/controller/state/grf_delay.hpp"

#include <cmath>

namespace hyq {

namespace {
constexpr int kSlots = kMaxGrfDelay + 1;
}

void GrfDelayLine::reset(int delay) {
  delay_ = delay < 0 ? 0 : (delay > kMaxGrfDelay ? kMaxGrfDelay : delay);
  next_ = 0;
  count_ = 0;
  for (Slot& s : slots_) {
    s.R_wb.setIdentity();
    for (int i = 0; i < 4; ++i) {
      s.parts[i] = GrfParts{};
      s.slip_velocity[i].setZero();
      s.slip_valid[i] = false;
    }
  }
}

void GrfDelayLine::pushSlipVelocity(int leg, const Vec3& v, bool valid) {
  slots_[next_].slip_velocity[leg] = v;
  slots_[next_].slip_valid[leg] = valid;
}

void GrfDelayLine::advance() {
  next_ = (next_ + 1) % kSlots;
  if (count_ < kSlots) ++count_;
}

int GrfDelayLine::oldest() const {
  // The last closed slot is next_ - 1; D before it is next_ - 1 - D.
  return (next_ - 1 - delay_ + 2 * kSlots) % kSlots;
}

Vec3 GrfDelayLine::force(int leg, const Vec3& qdd_leg, const Vec3& alpha_base) const {
  const Slot& s = slots_[oldest()];
  return forceFromParts(s.R_wb, s.parts[leg], qdd_leg, alpha_base);
}

double GrfDelayLine::forceSigma(int leg, const Vec3& qdd_sigma_leg, const Vec3& alpha_sigma) const {
  const GrfParts& p = slots_[oldest()].parts[leg];
  double sq = 0.0;
  for (int c = 0; c < 3; ++c) {
    sq += (p.jt_inverse * p.massColumn(c)).squaredNorm() * qdd_sigma_leg[c] * qdd_sigma_leg[c];
    sq += (p.jt_inverse * p.alpha_torque.col(c)).squaredNorm() * alpha_sigma[c] * alpha_sigma[c];
  }
  return std::sqrt(sq);
}

Vec3 GrfDelayLine::slipVelocity(int leg) const { return slots_[oldest()].slip_velocity[leg]; }

bool GrfDelayLine::slipVelocityValid(int leg) const {
  return ready() && slots_[oldest()].slip_valid[leg];
}

}  // namespace hyq
