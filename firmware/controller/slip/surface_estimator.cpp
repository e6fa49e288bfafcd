#include "firmware/controller/slip/surface_estimator.hpp"

#include <cmath>

#include "firmware/controller/model/sincos.hpp"

namespace hyq {

namespace {

// A plane's normal, made unit; false (and `unit` kept) for a vector
// shorter than 0.5 or not finite: no plane.
bool toUnitNormal(const Vec3& normal, Vec3& unit) {
  const double norm = normal.norm();
  if (!(std::isfinite(norm) && norm > 0.5 && normal.allFinite())) return false;
  unit = normal / norm;
  return true;
}

int clampWindow(int n) {
  if (n < 1) return 1;
  return n > kMaxEstimateSamples ? kMaxEstimateSamples : n;
}

// Below this sine, two unit vectors are treated as parallel or antipodal.
constexpr double kParallelSine = 1e-12;

// Below this sine, angleOverSine sums its series (8.6 deg).
constexpr double kSeriesSine = 0.15;

// The angle between two unit vectors over its sine, from s = sin and c = cos
// of it (s > 0): the logarithm map's scale. Near the mean, where the samples
// lie, asin(s) / s by its Maclaurin series in z = s^2, the coefficients
// (2n)! / (4^n n!^2 (2n + 1)) to n = 9: the first left out, about z^10 / 119,
// is under 3e-19 below kSeriesSine, far below the last bit of 1. Elsewhere
// the angle from angleOfSineCosine (a libm call, dearer on the board).
double angleOverSine(double s, double c) {
  if (c > 0.0 && s < kSeriesSine) {
    const double z = s * s;
    constexpr double k1 = 1.0 / 6.0, k2 = 3.0 / 40.0, k3 = 5.0 / 112.0, k4 = 35.0 / 1152.0, k5 = 63.0 / 2816.0,
                     k6 = 231.0 / 13312.0, k7 = 143.0 / 10240.0, k8 = 6435.0 / 557056.0, k9 = 12155.0 / 1245184.0;
    return 1.0 + z * (k1 + z * (k2 + z * (k3 + z * (k4 + z * (k5 + z * (k6 + z * (k7 + z * (k8 + z * k9))))))));
  }
  return angleOfSineCosine(s, c) / s;
}

}  // namespace

Vec3 sphericalMean(const Vec3* samples, int count, const Vec3& start, int iterations, double tolerance) {
  Vec3 mean = start.norm() > 0.0 ? Vec3(start.normalized()) : Vec3(Vec3::UnitZ());
  if (count <= 0) return mean;
  for (int it = 0; it < iterations; ++it) {
    // Average of the samples in the tangent plane at the current mean
    // (logarithm map), then one step along that geodesic (exponential map).
    Vec3 tangent_sum = Vec3::Zero();
    int used = 0;
    for (int i = 0; i < count; ++i) {
      const double c = mean.dot(samples[i]);
      const Vec3 ortho = samples[i] - c * mean;
      const double s = ortho.norm();
      if (s < kParallelSine) {
        if (c > 0.0) ++used;  // the sample sits on the mean: zero tangent
        continue;             // antipodal: no defined direction, skip it
      }
      tangent_sum += angleOverSine(s, c) * ortho;
      ++used;
    }
    if (used == 0) break;
    const Vec3 step = tangent_sum / static_cast<double>(used);
    const double angle = step.norm();
    if (angle < kParallelSine) break;
    const SinCos turn = sinCos(angle);
    mean = (turn.c * mean + turn.s / angle * step).normalized();
    if (angle < tolerance) break;  // the next step would be smaller still
  }
  return mean;
}

void SurfaceEstimator::reset(const SlipParams& params, double dt) {
  params_ = params;
  max_elevation_sine_ = std::sin(params.max_slip_elevation);
  min_force_angle_sine_ = std::sin(params.min_force_slip_angle);
  max_tilt_cosine_ = std::cos(params.max_normal_tilt);
  friction_angle_cosine_ = std::cos(params.max_friction_slip_angle);
  switch_angle_sine_ = std::sin(params.prior_switch_angle);
  dt_ = dt;
  peak_hold_ticks_ = 0;
  if (params.ending_peak_hold > 0.0 && dt > 0.0) {
    const double ticks = std::round(params.ending_peak_hold / dt);
    peak_hold_ticks_ = ticks < 1.0 ? 1 : ticks > 1e6 ? 1000000 : static_cast<int>(ticks);
  }
  slide_window_ = params.slide_window < 2 ? 2 : params.slide_window;
  if (slide_window_ > kMaxSlideWindow) slide_window_ = kMaxSlideWindow;
  history_next_ = 0;
  history_count_ = 0;
  window_n_ = clampWindow(params.estimate_samples_n);
  window_mu_ = clampWindow(params.estimate_samples_mu);
  min_samples_ = clampWindow(params.min_estimate_samples);
  clearSamples();
  was_slipping_ = false;
  normal_ = Vec3::UnitZ();
  slip_normal_ = Vec3::UnitZ();
  has_prior_ = false;
  prior_ = Vec3::UnitZ();
  has_alternative_ = false;
  use_alternative_ = false;
  alternative_ = Vec3::UnitZ();
  travel_ = Vec3::Zero();
  last_sample_foot_ = Vec3::Constant(1e9);
  mu_ = 0.0;
  last_normal_sample_ = Vec3::UnitZ();
}

void SurfaceEstimator::clearSamples() {
  next_ = 0;
  count_ = 0;
  own_ = 0;
  carried_ = 0;
  startEvent();
}

void SurfaceEstimator::startEvent() {
  peak_speed_ = 0.0;
  bucket_now_ = 0.0;
  bucket_before_ = 0.0;
  bucket_age_ = 0;
  stopped_ = false;
  moved_ = false;
}

void SurfaceEstimator::checkCarried() {
  const int carried = count_ - own_ < carried_ ? count_ - own_ : carried_;  // the ring may have overwritten some
  if (carried <= 0) {
    carried_ = 0;
    return;
  }
  double own_sum = 0.0, carried_sum = 0.0;
  for (int k = 0; k < own_; ++k) own_sum += mus_[newest(k)];
  for (int k = own_; k < own_ + carried; ++k) carried_sum += mus_[newest(k)];
  const double own_mean = own_sum / own_, carried_mean = carried_sum / carried;
  // A slide that reads lower is other ground sooner than one that reads higher.
  const double agreement = own_mean > carried_mean ? carry_agreement_above_ : carry_agreement_;
  if (std::fabs(own_mean - carried_mean) > agreement * carried_mean) {
    count_ = own_;
    carried_ = 0;
  } else {
    carried_ = carried;
  }
}

bool SurfaceEstimator::update(const SurfaceInput& in) {
  setPrior(in.prior);
  setAlternativePrior(in.alternative_prior);
  const bool slipping = in.slipping;
  const Vec3& slip_velocity_world = in.slip_velocity;
  if (in.history_valid && slip_velocity_world.allFinite() && in.grf.allFinite()) {
    pushHistory(slip_velocity_world, in.grf);
  } else {
    history_count_ = 0;
  }
  if (slipping && !was_slipping_) {
    const bool same_ground = carry_enabled_ && carry_distance_ > 0.0 && count_ > 0 && own_ < carry_max_samples_ &&
                             (in.foot - last_sample_foot_).head<2>().norm() < carry_distance_;
    if (same_ground) {
      carried_ = count_;
      own_ = 0;
      startEvent();
    } else {
      clearSamples();
    }
    travel_ = Vec3::Zero();
  }
  was_slipping_ = slipping;
  if (slipping && slip_velocity_world.allFinite()) travel_ += slip_velocity_world * dt_;
  // Only a slipping foot's samples use the prior.
  if (slipping)
    choosePrior();
  else
    use_alternative_ = false;
  if (!slipping) return false;
  foot_ = in.foot;
  return addSample(slip_velocity_world, in.grf, in.force_sigma);
}

bool SurfaceEstimator::addSample(const Vec3& v, const Vec3& force, double force_sigma) {
  if (!v.allFinite() || !force.allFinite() || !std::isfinite(force_sigma)) return false;
  const double speed = v.norm();
  const double force_norm = force.norm();
  if (!peak_of_loaded_) updatePeak(speed);
  if (peak_of_loaded_ && speed < params_.min_slip_speed && moved_) stopped_ = true;
  if (speed >= params_.min_slip_speed) moved_ = true;
  if (stopped_) return false;
  if (speed < params_.min_slip_speed || force_norm < params_.min_estimate_force) return false;
  if (params_.max_estimate_force_sigma > 0.0 && force_sigma > params_.max_estimate_force_sigma * force_norm)
    return false;
  // The slip is ending: a foot slowing down from its event's peak re-sticks,
  // and on a compliant contact its force falls inside the cone before the
  // foot stops.
  if (peak_of_loaded_ && speed > peak_speed_) peak_speed_ = speed;
  if (speed < params_.ending_slip_fraction * peak_speed_) return false;
  const Vec3 direction = v / speed;
  if (!slidingFriction(v, force)) return false;
  if (std::fabs(direction.z()) > max_elevation_sine_) return false;
  const double along = force.dot(direction);
  if (along > 0.0) return false;  // friction cannot push along the slip
  const Vec3 across = force - along * direction;
  const double across_norm = across.norm();
  if (across_norm < force_norm * min_force_angle_sine_) return false;
  const Vec3 normal = across / across_norm;
  if (normal.z() < max_tilt_cosine_) return false;
  // F . n_hat = |across| > 0 by construction; |F x n_hat| = |along|.
  const double mu = -along / across_norm;
  if (mu > params_.max_mu_estimate) return false;
  const double max_stiffness = params_.max_slide_stiffness;
  const double max_acceleration = params_.max_slide_acceleration;
  if (max_stiffness > 0.0 || max_acceleration > 0.0) {
    const SlideFit fit = slideFit(direction);
    if (max_stiffness > 0.0 && std::fabs(fit.stiffness) > max_stiffness) return false;
    if (max_acceleration > 0.0 && std::fabs(fit.acceleration) > max_acceleration) return false;
  }

  normals_[next_] = normal;
  mus_[next_] = mu;
  forces_[next_] = force;
  force_norms_[next_] = force_norm;
  speeds_[next_] = speed;
  next_ = (next_ + 1) % kMaxEstimateSamples;
  if (count_ < kMaxEstimateSamples) ++count_;
  if (own_ < kMaxEstimateSamples) ++own_;
  last_sample_foot_ = foot_;
  if (carried_ > 0 && own_ >= min_samples_) checkCarried();
  last_normal_sample_ = normal;
  refilter();
  return true;
}

void SurfaceEstimator::updatePeak(double speed) {
  // The fastest over the last one to two holds: two buckets of hold ticks
  // each, the older dropped as a new one starts (without a hold, one bucket
  // for the whole event).
  if (peak_hold_ticks_ > 0 && ++bucket_age_ > peak_hold_ticks_) {
    bucket_before_ = bucket_now_;
    bucket_now_ = 0.0;
    bucket_age_ = 1;
  }
  if (speed > bucket_now_) bucket_now_ = speed;
  peak_speed_ = bucket_now_ > bucket_before_ ? bucket_now_ : bucket_before_;
}

bool SurfaceEstimator::slidingFriction(const Vec3& v, const Vec3& force) const {
  const double max_angle = params_.max_friction_slip_angle;
  if (!(max_angle > 0.0) || !has_prior_) return true;
  // Along the ground (the prior's plane), sliding friction points against the
  // slip. A foot that moves while its contact still sticks (the pad's elastic
  // give, a rebound) carries a force inside the cone, in any direction; its
  // ratio is not mu. Without a prior there is no ground plane to test in.
  const Vec3& n = activePrior();
  const Vec3 f_t = force - force.dot(n) * n;
  const Vec3 v_t = v - v.dot(n) * n;
  const double f_norm = f_t.norm(), v_norm = v_t.norm();
  if (!(f_norm > 0.0) || !(v_norm > 0.0)) return false;
  return -f_t.dot(v_t) >= friction_angle_cosine_ * f_norm * v_norm;
}

void SurfaceEstimator::pushHistory(const Vec3& v, const Vec3& force) {
  history_velocity_[history_next_] = v;
  history_force_[history_next_] = force;
  history_next_ = (history_next_ + 1) & (kMaxSlideWindow - 1);
  if (history_count_ < kMaxSlideWindow) ++history_count_;
}

SurfaceEstimator::SlideFit SurfaceEstimator::slideFit(const Vec3& direction) const {
  SlideFit fit;
  const int n = slide_window_;
  if (history_count_ < n || !(dt_ > 0.0)) return fit;
  // Newest first, k = 0 the newest tick: the slip speed u along the current
  // slip direction, the travel s back from the newest tick (0 there,
  // negative before it), the force ratio r and the normal part w, in one
  // pass of sums. The acceleration is the least-squares slope of u on the
  // tick over the newest slide_window ticks. The stiffness is the slope of
  // r on s times the mean w, over those ticks and over the fewest ticks
  // (at least as many) whose travel reaches slide_travel, or the whole
  // history if it never does: the smaller of the two. A give shows over
  // both spans; the force estimate's noise, over a slow slide's short
  // travel, over the first alone (SlipParams::slide_travel).
  static_assert((kMaxSlideWindow & (kMaxSlideWindow - 1)) == 0, "a power of two: the ring index is a mask");
  constexpr unsigned kMask = kMaxSlideWindow - 1;
  const double centre = 0.5 * (n - 1);
  double travel = 0.0, u_newer = 0.0;
  double s_sum = 0.0, r_sum = 0.0, w_sum = 0.0, ss_sum = 0.0, sr_sum = 0.0, ku_sum = 0.0;
  bool ratio_defined = true;
  const auto stiffnessOver = [&](int count) {
    const double inv_count = 1.0 / count;
    const double sxx = ss_sum - s_sum * s_sum * inv_count;
    const double sxy = sr_sum - s_sum * r_sum * inv_count;
    return ratio_defined && sxx > 0.0 ? sxy / sxx * w_sum * inv_count : 0.0;
  };
  double window_stiffness = 0.0;
  int count = 0;
  for (int k = 0; k < history_count_; ++k) {  // history_count_ <= kMaxSlideWindow
    const unsigned idx = (static_cast<unsigned>(history_next_) - static_cast<unsigned>(k + 1)) & kMask;
    const double u = history_velocity_[idx].dot(direction);
    if (k < n) ku_sum += (centre - k) * u;  // centre - k: the tick's offset from the window's centre, oldest first
    if (k > 0) travel -= u_newer * dt_;
    u_newer = u;
    count = k + 1;
    const Vec3& f = history_force_[idx];
    const double along = f.dot(direction);
    const double across_sq = f.squaredNorm() - along * along;
    if (across_sq > 0.0) {
      const double across = std::sqrt(across_sq);
      const double r = -along / across;
      s_sum += travel;
      r_sum += r;
      w_sum += across;
      ss_sum += travel * travel;
      sr_sum += travel * r;
    } else {
      ratio_defined = false;
    }
    if (count == n) window_stiffness = stiffnessOver(n);
    if (count >= n && (params_.slide_travel <= 0.0 || -travel >= params_.slide_travel)) break;
  }
  const double kk_sum = n * (static_cast<double>(n) * n - 1.0) / 12.0;  // sum over k of (k - centre)^2
  fit.acceleration = ku_sum / kk_sum / dt_;
  // A tick without a ratio past the window leaves the window's fit alone.
  const double travel_stiffness = count > n && ratio_defined ? stiffnessOver(count) : window_stiffness;
  fit.stiffness = std::fabs(travel_stiffness) < std::fabs(window_stiffness) ? travel_stiffness : window_stiffness;
  return fit;
}

void SurfaceEstimator::setPrior(const Vec3& normal) {
  has_prior_ = toUnitNormal(normal, prior_);
  if (!has_prior_) use_alternative_ = false;
}

void SurfaceEstimator::setGround(const Vec3& prior, const Vec3& alternative) {
  setPrior(prior);
  setAlternativePrior(alternative);
}

void SurfaceEstimator::setAlternativePrior(const Vec3& normal) {
  has_alternative_ = toUnitNormal(normal, alternative_);
  if (!has_alternative_) use_alternative_ = false;
}

void SurfaceEstimator::choosePrior() {
  // Decided afresh each tick from this event's travel; between events (no
  // travel yet) the own prior.
  use_alternative_ = false;
  const double min_angle = params_.prior_switch_angle;
  if (!has_prior_ || !has_alternative_ || !(min_angle > 0.0)) return;
  const double length = travel_.norm();
  if (!(length >= params_.prior_switch_travel) || !(length > 0.0)) return;
  const double apart = prior_.cross(alternative_).norm();  // sine of the angle between the two
  if (!(apart > switch_angle_sine_)) return;
  // How far out of each plane the travel points (the sine of its elevation
  // from it): the alternative only if the travel lies in it, within half
  // their separation, and closer to it than to the own plane by as much.
  const double off_own = std::fabs(travel_.dot(prior_)) / length;
  const double off_alternative = std::fabs(travel_.dot(alternative_)) / length;
  use_alternative_ = off_alternative < 0.5 * apart && off_alternative + 0.5 * apart < off_own;
}

Vec3 SurfaceEstimator::fuseWithPrior(const Vec3& slip_normal, int n_normals) const {
  const double sigma_prior = params_.normal_prior_sigma;
  const Vec3& prior = activePrior();
  if (!has_prior_ || !(sigma_prior > 0.0) || n_normals <= 0) return slip_normal;
  // The event's slip-based normal: a direction error, the slip velocity's
  // noise over the window's mean slip speed (a slow slip's direction is
  // uncertain), and the GRF error across the slip over the mean normal force.
  double normal_force = 0.0, speed = 0.0;
  for (int k = 0; k < n_normals; ++k) {
    normal_force += forces_[newest(k)].dot(slip_normal);
    speed += speeds_[newest(k)];
  }
  normal_force /= static_cast<double>(n_normals);
  speed /= static_cast<double>(n_normals);
  if (!(normal_force > 0.0) || !(speed > 0.0)) return prior;
  const double force_angle = params_.estimate_force_sigma / normal_force;
  const double speed_angle = params_.slip_velocity_sigma / speed;
  const double var_slip = params_.slip_direction_sigma * params_.slip_direction_sigma +
                          speed_angle * speed_angle + force_angle * force_angle;
  const double var_prior = sigma_prior * sigma_prior;
  const double t = var_prior / (var_prior + var_slip);  // 0: the prior, 1: the slip estimate
  // Inverse-variance point on the geodesic from the prior to the slip normal.
  const double c = prior.dot(slip_normal);
  const Vec3 ortho = slip_normal - c * prior;
  const double s = ortho.norm();
  if (s < kParallelSine) return c > 0.0 ? slip_normal : prior;
  const double angle = t * angleOfSineCosine(s, c);
  const SinCos turn = sinCos(angle);
  return (turn.c * prior + turn.s / s * ortho).normalized();
}

void SurfaceEstimator::refilter() {
  // Newest sample first: newest(k) = (next_ - 1 - k) mod capacity.
  Vec3 recent[kMaxEstimateSamples];
  const int n_normals = count_ < window_n_ ? count_ : window_n_;
  Vec3 chord_sum = Vec3::Zero();
  for (int k = 0; k < n_normals; ++k) {
    recent[k] = normals_[newest(k)];
    chord_sum += recent[k];
  }
  // The normalised chordal mean is a close start; the Karcher iterations
  // then move it onto the true geodesic mean.
  const Vec3 start = chord_sum.norm() > 1e-9 ? chord_sum : recent[0];
  slip_normal_ =
      sphericalMean(recent, n_normals, start, params_.normal_mean_iterations, params_.normal_mean_tolerance);
  normal_ = fuseWithPrior(slip_normal_, n_normals);

  // mu = tan of the angle between F and the normal (Eq. 3), taken against
  // the filtered normal: a single sample's normal inherits the error of that
  // tick's slip direction (a few degrees of it tilt toward F's large normal
  // part and inflate mu by sin(err) / mu), the filtered one much less.
  const int n_mu = count_ < window_mu_ ? count_ : window_mu_;
  // |F x n| from |F| and F . n: (|F| - F . n)(|F| + F . n) = |F|^2 - (F . n)^2.
  double weighted = 0.0;
  double w = static_cast<double>(n_mu);  // newest: n_mu, oldest: 1
  for (int k = 0; k < n_mu; ++k, w -= 1.0) {
    const int idx = newest(k);
    const double along_normal = forces_[idx].dot(normal_);
    double mu = mus_[idx];
    if (along_normal > 0.0) {
      const double f = force_norms_[idx];
      const double across_sq = (f - along_normal) * (f + along_normal);
      mu = (across_sq > 0.0 ? std::sqrt(across_sq) : 0.0) / along_normal;
    }
    weighted += w * mu;
  }
  const double weight_sum = 0.5 * n_mu * (n_mu + 1.0);  // 1 + 2 + ... + n_mu
  mu_ = weighted / weight_sum;
}

}  // namespace hyq
