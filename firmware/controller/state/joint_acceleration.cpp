#include "firmware/controller/state/joint_acceleration.hpp"

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
  sigma_.setConstant(kUnknownSigma);
  for (Vec& h : history_) h.setZero();
}

template <int Dim>
typename SlopeFilter<Dim>::Vec SlopeFilter<Dim>::update(const Vec& qd) {
  if (!qd.allFinite()) {
    count_ = 0;
    qdd_.setZero();
    sigma_.setConstant(kUnknownSigma);
    return qdd_;
  }
  history_[next_] = qd;
  next_ = (next_ + 1) % window_;
  if (count_ < window_) ++count_;
  const int n = count_;
  if (n < 2) {
    qdd_.setZero();
    sigma_.setConstant(kUnknownSigma);
    return qdd_;
  }
  // Sample k (0 = oldest) sits at time k dt; slope = sum (k - kbar) v_k / sum (k - kbar)^2.
  const double kbar = 0.5 * static_cast<double>(n - 1);
  double denom = 0.0;
  Vec num = Vec::Zero();
  Vec sum = Vec::Zero();
  for (int k = 0; k < n; ++k) {
    const int idx = (next_ - n + k + window_) % window_;
    const double c = static_cast<double>(k) - kbar;
    num += c * history_[idx];
    sum += history_[idx];
    denom += c * c;
  }
  qdd_ = num / (denom * dt_);
  if (n < 3) {
    sigma_.setConstant(kUnknownSigma);
    return qdd_;
  }
  // The slope per tick, for the residuals only: qdd_ above keeps its own
  // rounding (num / (denom dt)), on which the closed-loop runs depend bit for bit.
  const Vec slope = num / denom;  // [rad/s per tick]
  // Residual sum of squares about the fitted line, v_k - mean - slope c_k.
  const Vec mean = sum / static_cast<double>(n);
  Vec rss = Vec::Zero();
  for (int k = 0; k < n; ++k) {
    const int idx = (next_ - n + k + window_) % window_;
    const double c = static_cast<double>(k) - kbar;
    rss += (history_[idx] - mean - c * slope).cwiseAbs2();
  }
  sigma_ = (rss / (static_cast<double>(n - 2) * denom)).cwiseSqrt() / dt_;
  return qdd_;
}

template class SlopeFilter<kNumJoints>;
template class SlopeFilter<3>;

}  // namespace hyq
