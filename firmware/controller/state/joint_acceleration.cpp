#include "firmware/controller/state/joint_acceleration.hpp"

#include <cmath>
#include <limits>

namespace hyq {

namespace {
// Fewer than three samples leave no scatter to measure: the slope is
// taken as uncertain (a sample resting on it is not used).
constexpr double kUnknownSigma = std::numeric_limits<double>::infinity();
}  // namespace

template <int Dim>
void SlopeFilter<Dim>::reset(int window, double dt) {
  window_ = window < 2 ? 2 : (window > kMaxAccelWindow ? kMaxAccelWindow : window);
  dt_ = dt > 0.0 ? dt : kTickPeriod;
  next_ = 0;
  count_ = 0;
  qdd_.setZero();
  weighted_sum_.setZero();
  offset_sq_sum_ = 0.0;
  offsets_n_ = 0;
  for (Vec& h : history_) h.setZero();
}

template <int Dim>
int SlopeFilter<Dim>::orderedSamples(const double* (&samples)[kMaxAccelWindow]) const {
  const int n = count_;
  int idx = (next_ - n + window_) % window_;
  for (int k = 0; k < n; ++k) {  // n <= window_ <= kMaxAccelWindow
    samples[k] = history_[idx].data();
    idx = idx + 1 == window_ ? 0 : idx + 1;
  }
  return n;
}

template <int Dim>
void SlopeFilter<Dim>::record(const Vec& qd) {
  if (!qd.allFinite()) {
    count_ = 0;
    return;
  }
  history_[next_] = qd;
  next_ = (next_ + 1) % window_;
  if (count_ < window_) ++count_;
}

template <int Dim>
typename SlopeFilter<Dim>::Vec SlopeFilter<Dim>::update(const Vec& qd) {
  record(qd);
  const double* samples[kMaxAccelWindow];
  const int n = orderedSamples(samples);
  if (n < 2) {
    qdd_.setZero();
    return qdd_;
  }
  // Sample k (0 = oldest) sits at time k dt; slope = sum (k - kbar) v_k / sum (k - kbar)^2.
  // The offsets and their squares' sum depend on n alone: computed again
  // only when n changes (filling the window, after a restart).
  if (n != offsets_n_) {
    const double kbar = 0.5 * static_cast<double>(n - 1);
    double denom = 0.0;
    for (int k = 0; k < n; ++k) {
      offsets_[k] = static_cast<double>(k) - kbar;
      denom += offsets_[k] * offsets_[k];
    }
    offset_sq_sum_ = denom;
    offsets_n_ = n;
  }
  const double* offsets = offsets_;
  const double denom = offset_sq_sum_;
  // Every channel's sum in a register (the board's 16 double registers hold
  // the 12), each summed in the order of the samples.
  static_assert(Dim <= 12, "one pass holds at most 12 sums");
  double num[Dim];
#pragma GCC unroll 12
  for (int j = 0; j < Dim; ++j) num[j] = 0.0;
  for (int k = 0; k < n; ++k) {
    const double* v = samples[k];
#pragma GCC unroll 12
    for (int j = 0; j < Dim; ++j) num[j] += offsets[k] * v[j];
  }
#pragma GCC unroll 12
  for (int j = 0; j < Dim; ++j) weighted_sum_[j] = num[j];
  qdd_ = weighted_sum_ / (denom * dt_);
  return qdd_;
}

template <int Dim>
Vec3 SlopeFilter<Dim>::accelerationSigma(int first) const {
  const double* samples[kMaxAccelWindow];
  const int n = orderedSamples(samples);
  if (n < 3) return Vec3::Constant(kUnknownSigma);
  // The slope per tick, from update()'s sums, and the mean of each channel.
  const double denom = offset_sq_sum_;
  const Vec3 slope = weighted_sum_.template segment<3>(first) / denom;  // [rad/s per tick]
  double sum[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < n; ++k) {
#pragma GCC unroll 3
    for (int j = 0; j < 3; ++j) sum[j] += samples[k][first + j];
  }
  const Vec3 mean = Vec3(sum[0], sum[1], sum[2]) / static_cast<double>(n);
  // Residual sum of squares about the fitted line, v_k - mean - slope c_k.
  const double kbar = 0.5 * static_cast<double>(n - 1);
  double rss[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < n; ++k) {
    const double c = static_cast<double>(k) - kbar;
    const double* v = samples[k] + first;
#pragma GCC unroll 3
    for (int j = 0; j < 3; ++j) {
      const double residual = v[j] - mean[j] - c * slope[j];
      rss[j] += residual * residual;
    }
  }
  const double scale = static_cast<double>(n - 2) * denom;
  return Vec3(std::sqrt(rss[0] / scale) / dt_, std::sqrt(rss[1] / scale) / dt_, std::sqrt(rss[2] / scale) / dt_);
}

template <int Dim>
typename SlopeFilter<Dim>::Vec SlopeFilter<Dim>::accelerationSigma() const {
  static_assert(Dim % 3 == 0, "channels in threes");
  Vec sigma;
  for (int first = 0; first < Dim; first += 3) sigma.template segment<3>(first) = accelerationSigma(first);
  return sigma;
}

template class SlopeFilter<kNumJoints>;
template class SlopeFilter<3>;

}  // namespace hyq
