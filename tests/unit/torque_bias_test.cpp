// Joint-torque offsets learnt in swing: the estimate converges on the offset
// through the sensor's noise, also when the residual it is fed was computed
// with the estimate of a few ticks earlier (the GRF's acceleration window),
// per leg, within its clamp, and not at all when switched off.
#include "firmware/controller/state/torque_bias.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>

namespace hyq {
namespace {

constexpr double kDt = 0.001;

// Feeds leg `leg` `ticks` residuals of a reading with offset `offset` and
// white noise `sigma` [N m], corrected by the estimate `lag` ticks old.
// Returns the largest overshoot past the offset seen on any joint [N m].
double feed(TorqueBiasEstimator& est, int leg, const Vec3& offset, int ticks, double sigma, int lag,
            uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::deque<Vec3> past(static_cast<size_t>(lag + 1), est.bias(leg));
  double overshoot = 0.0;
  for (int k = 0; k < ticks; ++k) {
    const Vec3 used = past.front();
    est.update(leg, offset - used + Vec3(noise(rng), noise(rng), noise(rng)));
    past.pop_front();
    past.push_back(est.bias(leg));
    for (int j = 0; j < 3; ++j) {
      const double past_offset = offset[j] > 0.0 ? est.bias(leg)[j] - offset[j] : offset[j] - est.bias(leg)[j];
      overshoot = std::max(overshoot, past_offset);
    }
  }
  return overshoot;
}

TEST(TorqueBias, OneSwingOfNoisyResidualsFindsTheOffset) {
  EstimatorParams p;
  const Vec3 offset(0.6, -0.4, 0.9);
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    TorqueBiasEstimator est;
    est.reset(p, kDt);
    // About 1000 samples (the sampled part of a swing is ~0.6 s, so a swing
    // and a half) at the torque sensor's 0.5 N m noise, lagged by 5 ticks
    // (the acceleration window's centre is 4). The mean of 1000 samples with
    // 100 of start weight: 9 % of the offset left, plus 0.5 / sqrt(1000) =
    // 0.016 N m of noise.
    feed(est, 2, offset, 1000, 0.5, 5, seed);
    EXPECT_LT((est.bias(2) - offset).cwiseAbs().maxCoeff(), 0.15) << "seed " << seed;
    // 4000 samples on: the exponential average over the last 1000.
    feed(est, 2, offset, 4000, 0.5, 5, seed + 10);
    EXPECT_LT((est.bias(2) - offset).cwiseAbs().maxCoeff(), 0.05) << "seed " << seed;
  }
}

TEST(TorqueBias, TheLaggedResidualDoesNotOvershoot) {
  // Without noise the running mean approaches the offset from below; a step
  // too large for the 5-tick lag would carry it past.
  EstimatorParams p;
  TorqueBiasEstimator est;
  est.reset(p, kDt);
  const double overshoot = feed(est, 0, Vec3(1.0, -1.0, 2.0), 6000, 0.0, 5, 1);
  EXPECT_LT(overshoot, 1e-9);
  EXPECT_NEAR(est.bias(0).z(), 2.0, 0.01);
  // Without the start weight the lagged mean runs past the offset.
  p.torque_bias_start_weight = 0.0;
  est.reset(p, kDt);
  EXPECT_GT(feed(est, 0, Vec3(1.0, -1.0, 2.0), 6000, 0.0, 5, 1), 0.5);
}

TEST(TorqueBias, LegsAreIndependent) {
  EstimatorParams p;
  TorqueBiasEstimator est;
  est.reset(p, kDt);
  feed(est, 1, Vec3(0.5, 0.5, 0.5), 2000, 0.1, 0, 3);
  EXPECT_EQ(est.bias(0), Vec3::Zero());
  EXPECT_EQ(est.bias(2), Vec3::Zero());
  EXPECT_EQ(est.bias(3), Vec3::Zero());
  EXPECT_GT(est.bias(1).minCoeff(), 0.4);
}

TEST(TorqueBias, AnImplausibleOffsetIsClampedAndOffLearnsNothing) {
  EstimatorParams p;
  TorqueBiasEstimator est;
  est.reset(p, kDt);
  feed(est, 3, Vec3(2.0 * p.torque_bias_limit, -2.0 * p.torque_bias_limit, 0.0), 3000, 0.0, 0, 4);
  EXPECT_DOUBLE_EQ(est.bias(3).x(), p.torque_bias_limit);
  EXPECT_DOUBLE_EQ(est.bias(3).y(), -p.torque_bias_limit);
  p.torque_bias_time = 0.0;
  est.reset(p, kDt);
  feed(est, 3, Vec3(1.0, 1.0, 1.0), 1000, 0.0, 0, 5);
  EXPECT_EQ(est.bias(3), Vec3::Zero());
}

TEST(TorqueBias, WhatIsNotYetLearntIsTheRemainingSigma) {
  // Without noise and lag the estimate after k samples holds k / (k + k0) of
  // the offset; remainingSigma says the same of the prior spread, and it
  // bounds the error left when the offset is one prior sigma.
  EstimatorParams p;
  TorqueBiasEstimator est;
  est.reset(p, kDt);
  const double k0 = p.torque_bias_start_weight;
  EXPECT_DOUBLE_EQ(est.remainingSigma(2), p.torque_offset_sigma);  // nothing learnt yet
  const double offset = p.torque_offset_sigma;
  for (int k = 1; k <= 600; ++k) {
    feed(est, 2, Vec3(offset, -offset, offset), 1, 0.0, 0, 6);
    if (k == 100 || k == 600) {
      EXPECT_NEAR(est.remainingSigma(2), p.torque_offset_sigma * k0 / (k + k0), 1e-12);
      EXPECT_NEAR(std::fabs(offset - est.bias(2).x()), est.remainingSigma(2), 1e-9) << k;
    }
  }
  // One swing's ~600 samples leave 1/7 with the default start weight.
  EXPECT_NEAR(est.remainingSigma(2), p.torque_offset_sigma * k0 / (600.0 + k0), 1e-12);
  EXPECT_NEAR(k0 / (600.0 + k0), 1.0 / 7.0, 1e-12);
  EXPECT_DOUBLE_EQ(est.remainingSigma(0), p.torque_offset_sigma);  // the other legs: still all of it
  // Switched off, the offsets are never learnt: all of the spread stays.
  p.torque_bias_time = 0.0;
  est.reset(p, kDt);
  feed(est, 2, Vec3(offset, offset, offset), 600, 0.0, 0, 7);
  EXPECT_DOUBLE_EQ(est.remainingSigma(2), p.torque_offset_sigma);
  // And with no spread assumed, nothing remains.
  p = EstimatorParams{};
  p.torque_offset_sigma = 0.0;
  est.reset(p, kDt);
  EXPECT_DOUBLE_EQ(est.remainingSigma(1), 0.0);
}

}  // namespace
}  // namespace hyq
