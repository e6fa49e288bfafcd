#include "firmware/controller/slip_detector.hpp"

namespace hyq {

namespace {

constexpr int kCounterCap = 1 << 20;  // keeps debounce counters from overflowing

bool inMask(uint32_t mask, int leg) { return (mask >> leg) & 1u; }

int countLegs(uint32_t mask) {
  int n = 0;
  for (int leg = 0; leg < kSlipLegs; ++leg) n += inMask(mask, leg) ? 1 : 0;
  return n;
}

// Median of up to kSlipLegs values (insertion sort; mean of the two middle
// values for an even count).
double median(const double* values, int n) {
  double sorted[kSlipLegs];
  for (int i = 0; i < n; ++i) {
    int j = i;
    while (j > 0 && sorted[j - 1] > values[i]) {
      sorted[j] = sorted[j - 1];
      --j;
    }
    sorted[j] = values[i];
  }
  if (n % 2 == 1) return sorted[n / 2];
  return 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

}  // namespace

void ImuVelocityIntegrator::reset(const SlipParams& params) {
  params_ = params;
  velocity_world_.setZero();
  velocity_base_.setZero();
  time_since_anchor_ = 0.0;
  anchored_ = false;
  valid_ = false;
}

void ImuVelocityIntegrator::update(const Vec3& specific_force_base,
                                   const Mat3& rotation_world_base,
                                   const Vec3& gravity_world, double dt,
                                   const Vec3& odometry_velocity_base,
                                   bool odometry_trusted) {
  const bool rotation_ok = rotation_world_base.allFinite();
  if (odometry_trusted && rotation_ok && odometry_velocity_base.allFinite()) {
    velocity_world_ = rotation_world_base * odometry_velocity_base;
    time_since_anchor_ = 0.0;
    anchored_ = true;
  }
  const bool step_ok = rotation_ok && specific_force_base.allFinite() &&
                       gravity_world.allFinite() && dt > 0.0 && dt < 1.0;
  if (step_ok) {
    velocity_world_ += (rotation_world_base * specific_force_base + gravity_world) * dt;
    velocity_base_ = rotation_world_base.transpose() * velocity_world_;
  }
  if (dt > 0.0 && dt < 1.0) time_since_anchor_ += dt;
  // An integration older than the window has drifted too far to judge legs
  // by; the detector then falls back to the median test alone.
  constexpr double kClockRounding = 1e-9;  // [s] summed ticks vs the window
  valid_ = anchored_ && step_ok &&
           time_since_anchor_ <= params_.imu_integration_window + kClockRounding;
}

void SlipDetector::reset(const SlipParams& params) {
  params_ = params;
  for (int leg = 0; leg < kSlipLegs; ++leg) {
    detect_count_[leg] = 0;
    clear_count_[leg] = 0;
  }
  slip_mask_ = 0;
}

bool SlipDetector::agree(const SlipInput& in, uint32_t legs, double tolerance) const {
  // Pairwise: no two of these feet move relative to each other faster than
  // the tolerance.
  if (legs == 0) return false;
  for (int a = 0; a < kSlipLegs; ++a) {
    if (!inMask(legs, a)) continue;
    for (int b = a + 1; b < kSlipLegs; ++b)
      if (inMask(legs, b) && (in.u[a] - in.u[b]).norm() > tolerance) return false;
  }
  return true;
}

bool SlipDetector::imuConfirms(const SlipInput& in, uint32_t legs) const {
  Vec3 mean = Vec3::Zero();
  for (int leg = 0; leg < kSlipLegs; ++leg)
    if (inMask(legs, leg)) mean += in.u[leg];
  mean /= static_cast<double>(countLegs(legs));
  return (mean + in.imu_base_velocity).norm() <= params_.multi_leg_consistency;
}

uint32_t SlipDetector::medianTest(const SlipInput& in, uint32_t usable,
                                  SlipResult& out) const {
  double speeds[kSlipLegs];
  int n = 0;
  for (int leg = 0; leg < kSlipLegs; ++leg)
    if (inMask(usable, leg)) speeds[n++] = in.u[leg].norm();
  if (n == 0) return 0;
  out.median_speed = median(speeds, n);
  uint32_t flags = 0;
  for (int leg = 0; leg < kSlipLegs; ++leg) {
    if (!inMask(usable, leg)) continue;
    const double s = in.u[leg].norm();
    const double diff = s > out.median_speed ? s - out.median_speed : out.median_speed - s;
    if (diff > params_.threshold) flags |= 1u << leg;
  }
  return flags;
}

uint32_t SlipDetector::imuTest(const SlipInput& in, uint32_t usable) const {
  uint32_t flags = 0;
  for (int leg = 0; leg < kSlipLegs; ++leg) {
    if (!inMask(usable, leg)) continue;
    if ((in.u[leg] + in.imu_base_velocity).norm() > params_.multi_leg_consistency)
      flags |= 1u << leg;
  }
  return flags;
}

void SlipDetector::debounce(uint32_t stance, uint32_t usable, uint32_t raw, uint32_t landing) {
  const int raise_stance = params_.debounce_ticks < 1 ? 1 : params_.debounce_ticks;
  const int extra = params_.landing_debounce_extra < 0 ? 0 : params_.landing_debounce_extra;
  const int drop_after = params_.release_ticks < 1 ? 1 : params_.release_ticks;
  for (int leg = 0; leg < kSlipLegs; ++leg) {
    const uint32_t bit = 1u << leg;
    if (!inMask(stance, leg)) {
      detect_count_[leg] = 0;
      clear_count_[leg] = 0;
      slip_mask_ &= ~bit;
      continue;
    }
    if (!inMask(usable, leg)) continue;  // no valid measurement: hold
    if (inMask(raw, leg)) {
      clear_count_[leg] = 0;
      if (detect_count_[leg] < kCounterCap) ++detect_count_[leg];
      const int raise_after = inMask(landing, leg) ? raise_stance + extra : raise_stance;
      if (detect_count_[leg] >= raise_after) slip_mask_ |= bit;
    } else {
      detect_count_[leg] = 0;
      if (clear_count_[leg] < kCounterCap) ++clear_count_[leg];
      if (clear_count_[leg] >= drop_after) slip_mask_ &= ~bit;
    }
  }
}

void SlipDetector::slipVelocities(const SlipInput& in, uint32_t usable,
                                  SlipResult& out) const {
  const uint32_t reference = usable & ~(out.raw_mask | slip_mask_);
  const int n_ref = countLegs(reference);
  if (n_ref >= 2 || (n_ref == 1 && !in.imu_velocity_valid)) {
    Vec3 sum = Vec3::Zero();
    for (int leg = 0; leg < kSlipLegs; ++leg)
      if (inMask(reference, leg)) sum += in.u[leg];
    out.u_reference = sum / static_cast<double>(n_ref);
  } else if (in.imu_velocity_valid) {
    out.u_reference = -in.imu_base_velocity;
  } else {
    return;  // no foot and no IMU to measure slip against
  }
  if (!in.rotation_world_base.allFinite()) return;
  out.base_velocity_legs = -out.u_reference;
  out.slip_velocity_valid = true;
  for (int leg = 0; leg < kSlipLegs; ++leg)
    if (inMask(usable, leg))
      out.slip_velocity_world[leg] = in.rotation_world_base * (in.u[leg] - out.u_reference);
}

SlipResult SlipDetector::update(const SlipInput& in_raw) {
  SlipInput in = in_raw;
  if (!in.imu_base_velocity.allFinite()) in.imu_velocity_valid = false;
  const uint32_t stance = in.stance_mask & ((1u << kSlipLegs) - 1u);
  uint32_t usable = 0;
  for (int leg = 0; leg < kSlipLegs; ++leg)
    if (inMask(stance, leg) && !inMask(in.hold_mask, leg) && in.u[leg].allFinite()) usable |= 1u << leg;
  const int n = countLegs(usable);

  // The tests compare velocities along the ground: a slip is motion in the
  // ground's plane, while a foot still settling (a landing foot's last
  // centimetres, a penalty contact's compression) moves along its normal.
  SlipInput along = in;
  const double normal_norm = in.ground_normal_base.norm();
  if (in.ground_normal_base.allFinite() && normal_norm > 0.5) {
    const Vec3 nb = in.ground_normal_base / normal_norm;
    for (int leg = 0; leg < kSlipLegs; ++leg) along.u[leg] -= nb.dot(in.u[leg]) * nb;
    along.imu_base_velocity -= nb.dot(in.imu_base_velocity) * nb;
  }

  SlipResult out;
  const uint32_t median_flags = medianTest(along, usable, out);
  const uint32_t holding = usable & ~median_flags;
  const int n_holding = countLegs(holding);
  bool median_trusted =
      n >= 3 && countLegs(median_flags) <= 1 && agree(along, holding, params_.holding_agreement);
  // Two agreeing feet against one cannot tell which side slips (two feet may
  // slide together): ask the IMU whether the pair really holds.
  if (median_trusted && n_holding < 3 && in.imu_velocity_valid)
    median_trusted = imuConfirms(along, holding);
  // The IMU anchor takes the full vectors: it uses their vertical part too.
  out.legs_agree =
      median_trusted && n_holding >= 3 && agree(in, holding, params_.imu_anchor_agreement);

  if (median_trusted) {
    out.raw_mask = median_flags;
    out.test = SlipTest::kMedian;
  } else if (in.imu_velocity_valid && n >= 1) {
    out.raw_mask = imuTest(along, usable);
    out.test = SlipTest::kImu;
  } else if (n >= 2) {
    out.raw_mask = median_flags;
    out.test = SlipTest::kMedianUnverified;
  }
  debounce(stance, usable, out.raw_mask, in.landing_mask & stance);
  out.slip_mask = slip_mask_;
  slipVelocities(in, usable, out);
  if (in.anchor_on_two_feet && out.test == SlipTest::kImu && n == 2 && out.slip_velocity_valid &&
      (usable & (out.raw_mask | out.slip_mask)) == 0 && agree(in, usable, params_.imu_anchor_agreement))
    out.legs_agree = true;
  return out;
}

}  // namespace hyq
