// Joint accelerations from the measured joint velocities, for the leg-inertia
// term of the ground-reaction-force estimate (Controller::computeLegs), and
// the base's angular acceleration from the gyro, for the links' share of the
// base's rotation in the same estimate: one filter, Dim channels.
//
// The least-squares slope of the last N velocity samples: differentiating
// one tick to the next would turn 0.01 rad/s of velocity noise into 10 rad/s^2;
// the slope over N samples has sigma_v / (dt sqrt(N (N^2 - 1) / 12)) of noise
// (1.1 rad/s^2 for N = 10) and lags the true acceleration by (N - 1) / 2
// ticks. Until N samples have arrived it uses the ones it has (zero with
// fewer than two). Fixed storage; every loop runs at most kMaxAccelWindow times.
#pragma once
#include "firmware/controller/model/types.hpp"

namespace hyq {

constexpr int kMaxAccelWindow = 32;

template <int Dim>
class SlopeFilter {
 public:
  using Vec = Eigen::Matrix<double, Dim, 1>;

  // window [ticks]: N, clamped to [2, kMaxAccelWindow]; dt [s] tick period.
  void reset(int window, double dt);
  // qd [rad/s]: this tick's joint velocities. A non-finite sample clears the
  // history (the estimate restarts from the next good samples).
  // Returns qdd [rad/s^2].
  Vec update(const Vec& qd);
  // The sample alone, without the slope: the history stays warm for a
  // later update() (acceleration() and accelerationSigma() then hold the
  // last update()'s).
  void record(const Vec& qd);
  Vec acceleration() const { return qdd_; }
  // [rad/s^2] standard error of each slope, from the scatter of the window's
  // samples about their line: the velocity noise alone gives ~1.1 rad/s^2
  // (N = 10); a kink in the window (an impact, a slip's onset) gives far
  // more, and the slope is then no acceleration of any one instant.
  // Infinite with fewer than three samples (after a reset or a bad sample).
  // Computed when asked, from the samples of the last update(): only a
  // slipping foot's sample needs it.
  Vec accelerationSigma() const;
  // The same of the three channels from `first` (a leg's joints).
  Vec3 accelerationSigma(int first) const;
  // [ticks] how far back the estimate is centred: (N - 1) / 2, rounded down.
  int centreLag() const { return (window_ - 1) / 2; }

 private:
  // The window's samples, oldest first: pointers into history_.
  int orderedSamples(const double* (&samples)[kMaxAccelWindow]) const;

  Vec history_[kMaxAccelWindow];
  int window_ = 10;
  int next_ = 0;
  int count_ = 0;
  double dt_ = kTickPeriod;
  Vec qdd_ = Vec::Zero();
  // The last update's sums over the window, kept for accelerationSigma:
  // sum (k - kbar) v_k and sum (k - kbar)^2.
  Vec weighted_sum_ = Vec::Zero();
  double offset_sq_sum_ = 0.0;
  // Each sample's offset from the window's centre, k - kbar [ticks], for
  // offsets_n_ samples (0: not yet computed): the same every tick once the
  // window is full.
  double offsets_[kMaxAccelWindow] = {};
  int offsets_n_ = 0;
};

using JointAccelerationFilter = SlopeFilter<kNumJoints>;  // [rad/s] -> [rad/s^2], 12 joints
using AngularAccelerationFilter = SlopeFilter<3>;         // gyro [rad/s] -> [rad/s^2], B

}  // namespace hyq
