#include "sim_host/physics/actuator.hpp"

#include <algorithm>
#include <cmath>

namespace hyq::sim {
namespace {

constexpr double kTwoPi = 6.283185307179586;

// A first-order low-pass's gain for a sample period `dt` [s]: the exact
// discretisation of 1 / (1 + s / (2 pi fc)) for an input held over it.
double lowPassGain(double cutoff, double dt) { return 1.0 - std::exp(-kTwoPi * cutoff * dt); }

struct Mat2 {
  double m[2][2];
};

Mat2 multiply(const Mat2& a, const Mat2& b) {
  Mat2 c{};
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 2; ++k) c.m[i][k] = a.m[i][0] * b.m[0][k] + a.m[i][1] * b.m[1][k];
  return c;
}

// exp(a) by scaling and squaring a Taylor series: the 2 x 2 state matrices
// here have a norm of a few at most, so 2^-8 of them converges in 12 terms
// to double precision.
Mat2 exponential(const Mat2& a) {
  constexpr int kSquarings = 8;
  Mat2 s{};
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 2; ++k) s.m[i][k] = a.m[i][k] / (1 << kSquarings);
  Mat2 sum{{{1.0, 0.0}, {0.0, 1.0}}}, term = sum;
  for (int n = 1; n <= 12; ++n) {
    term = multiply(term, s);
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 2; ++k) term.m[i][k] /= n;
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 2; ++k) sum.m[i][k] += term.m[i][k];
  }
  for (int k = 0; k < kSquarings; ++k) sum = multiply(sum, sum);
  return sum;
}

}  // namespace

JointEncoder::JointEncoder(const EncoderParams& params) : params_(params) {}

double JointEncoder::quantise(double q, double step) { return step > 0.0 ? step * std::round(q / step) : q; }

double JointEncoder::velocityLag(double cutoff, double period) {
  return 0.5 * period + period / std::expm1(kTwoPi * cutoff * period);
}

void JointEncoder::reset(double q) {
  position_ = quantise(q, params_.resolution);
  velocity_ = 0.0;
}

void JointEncoder::sample(double q, double qd, double elapsed) {
  const double reading = quantise(q, params_.resolution);
  if (params_.velocity == VelocitySource::truth) {
    velocity_ = qd;
  } else if (elapsed > 0.0) {
    // The period is a sum of integration steps: equal periods differ in
    // their last bits, which need no new gain.
    if (std::fabs(elapsed - alpha_period_) > 1e-9 * elapsed) {
      alpha_period_ = elapsed;
      alpha_ = lowPassGain(params_.velocity_cutoff, elapsed);
    }
    velocity_ += alpha_ * ((reading - position_) / elapsed - velocity_);
  }
  position_ = reading;
}

JointActuator::JointActuator(const ActuatorParams& actuator, const EncoderParams& encoder, double effort_limit)
    : params_(actuator), effort_limit_(effort_limit), pd_period_(1.0 / actuator.pd_rate), encoder_(encoder) {}

void JointActuator::reset(double q, double tau) {
  encoder_.reset(q);
  since_sample_ = 0.0;
  demand_ = torque_ = sensor_ = std::clamp(tau, -effort_limit_, effort_limit_);
  rate_ = 0.0;
}

double JointActuator::pd(const JointCommand& c) const {
  double tau = c.tau_ff + c.kp * (c.q_ref - encoder_.position()) + c.kd * (c.qd_ref - encoder_.velocity());
  // A NaN command must not poison the physics: the board outputs nothing.
  if (!std::isfinite(tau)) tau = 0.0;
  return std::clamp(tau, -effort_limit_, effort_limit_);
}

void JointActuator::discretise(double dt) {
  dt_ = dt;
  const double w = kTwoPi * params_.bandwidth, z = params_.damping_ratio;
  // d/dt (torque, rate) = A (torque, rate) + (0, w^2) demand.
  const Mat2 a{{{0.0, dt}, {-w * w * dt, -2.0 * z * w * dt}}};
  const Mat2 phi = exponential(a);
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 2; ++k) phi_[i][k] = phi.m[i][k];
  // A held demand u has the rest state (u, 0): x+ - (u, 0) = phi (x - (u, 0)).
  gamma_[0] = 1.0 - phi_[0][0];
  gamma_[1] = -phi_[1][0];
  sensor_alpha_ = lowPassGain(params_.torque_sensor_cutoff, dt);
}

void JointActuator::integrate(double qd) {
  const double torque = phi_[0][0] * torque_ + phi_[0][1] * rate_ + gamma_[0] * demand_;
  double rate = phi_[1][0] * torque_ + phi_[1][1] * rate_ + gamma_[1] * demand_;
  const double limit = params_.rate_limit;
  double next = torque;
  if (std::fabs(rate) > limit || std::fabs(torque - torque_) > limit * dt_) {
    // Rate-limited: the torque moves at most limit * dt, and so fast no faster.
    rate = std::clamp(rate, -limit, limit);
    next = torque_ + std::clamp(torque - torque_, -limit * dt_, limit * dt_);
  }
  if (std::fabs(next) > effort_limit_) {
    next = std::clamp(next, -effort_limit_, effort_limit_);
    rate = 0.0;
  }
  const double v = params_.velocity_limit;
  if (v > 0.0 && next * qd > 0.0) {
    const double r = qd / v;
    const double cap = r * r < 1.0 ? effort_limit_ * (1.0 - r * r) : 0.0;  // [N m] along the motion
    if (std::fabs(next) > cap) {
      next = std::copysign(cap, next);
      rate = 0.0;
    }
  }
  torque_ = next;
  rate_ = rate;
  sensor_ += sensor_alpha_ * (torque_ - sensor_);
}

double JointActuator::step(const JointCommand& command, double q0, double qd0, double h) {
  const int n = std::max(1, static_cast<int>(std::ceil(h / kMaxIntegrationStep - 1e-9)));
  const double dt = h / n;
  if (dt != dt_) discretise(dt);
  // A PD period ends within a part per million of its length: the clock's
  // sum of integration steps is not exact.
  const double due = pd_period_ * (1.0 - 1e-6);
  double impulse = 0.0;
  for (int i = 0; i < n; ++i) {
    if (i == 0) {
      demand_ = pd(command);
    } else if (since_sample_ >= due) {
      encoder_.sample(q0 + qd0 * (i * dt), qd0, since_sample_);
      since_sample_ = 0.0;
      demand_ = pd(command);
    }
    const double before = torque_;
    integrate(qd0);
    impulse += 0.5 * (before + torque_) * dt;
    since_sample_ += dt;
  }
  return impulse / h;
}

void JointActuator::finishStep(double q1, double qd1) {
  if (since_sample_ < pd_period_ * (1.0 - 1e-6)) return;
  encoder_.sample(q1, qd1, since_sample_);
  since_sample_ = 0.0;
}

}  // namespace hyq::sim
