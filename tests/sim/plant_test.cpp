// The simulated plant (sim_host/physics/plant_params.hpp): the joints'
// actuator model against its design (step and frequency response, rate
// limit, saturation, torque sensor filter), the encoders' quantisation and
// velocity lag, the transport delays in whole ticks, the mounted IMU's lever
// arm, and the plant.* scenario keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/physics/actuator.hpp"
#include "sim_host/physics/sensors.hpp"
#include "sim_host/physics/simulator.hpp"
#include "sim_host/records/metrics.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A torque loop alone: no rate limit to speak of, the sensor fast.
ActuatorParams loopOnly(double bandwidth, double damping) {
  ActuatorParams a;
  a.model = true;
  a.bandwidth = bandwidth;
  a.damping_ratio = damping;
  a.rate_limit = 1e9;
  a.torque_sensor_cutoff = 5000.0;
  return a;
}

JointCommand torque(double tau) {
  JointCommand c;
  c.tau_ff = tau;
  return c;
}

// The time [s] a second-order lag of natural frequency wn [rad/s] and
// damping z < 1 takes to reach `fraction` of a step, from its closed-form
// step response, by bisection on its first rise.
double secondOrderRiseTime(double wn, double z, double fraction) {
  const double wd = wn * std::sqrt(1.0 - z * z);
  auto response = [&](double t) {
    return 1.0 - std::exp(-z * wn * t) * (std::cos(wd * t) + z * wn / wd * std::sin(wd * t));
  };
  double lo = 0.0, hi = kPi / wd;  // the response rises monotonically to its first peak
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    (response(mid) < fraction ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// A step of commanded torque reaches 63.2 % of the step at the time the
// closed-form response of the set second-order lag gives (the
// second-order equivalent of a first-order lag's 1/(2 pi f) at its
// bandwidth f), within 5 %, at 30, 40 and 60 Hz; at damping 1/sqrt(2)
// (the -3 dB bandwidth equal to the natural frequency) that time is
// 1.75 / (2 pi f): 6.97 ms at 40 Hz.
TEST(Actuator, StepReaches63PercentWhenTheSetLagSays) {
  for (double f : {30.0, 40.0, 60.0}) {
    const double z = 1.0 / std::sqrt(2.0);
    JointActuator act(loopOnly(f, z), EncoderParams{}, 150.0);
    act.reset(0.0, 0.0);
    const double h = 1e-5, step = 100.0;
    double t63 = -1.0;
    for (int k = 0; k < 100000 && t63 < 0.0; ++k) {
      act.step(torque(step), 0.0, 0.0, h);
      if (act.delivered() >= 0.632 * step) t63 = (k + 1) * h;
    }
    const double expected = secondOrderRiseTime(2.0 * kPi * f, z, 0.632);
    std::printf("%g Hz: 63.2 %% after %.3f ms, the set lag's %.3f ms (1/(2 pi f) = %.3f ms)\n", f, 1e3 * t63,
                1e3 * expected, 1e3 / (2.0 * kPi * f));
    EXPECT_NEAR(t63, expected, 0.05 * expected) << f << " Hz";
  }
}

// At the set bandwidth, a sinusoidal torque command comes through at
// -3 dB (amplitude ratio 1/sqrt(2)) within 5 % with damping 1/sqrt(2).
TEST(Actuator, SinusoidAtTheBandwidthComesThroughAtMinus3Db) {
  const double f = 40.0, h = 1e-3;
  JointActuator act(loopOnly(f, 1.0 / std::sqrt(2.0)), EncoderParams{}, 150.0);
  act.reset(0.0, 0.0);
  double peak = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * h;
    act.step(torque(10.0 * std::sin(2.0 * kPi * f * t)), 0.0, 0.0, h);
    if (t > 1.0) peak = std::max(peak, std::fabs(act.delivered()));  // after the start has died away
  }
  // Sampled once a tick, 25 times a period, the peak is found within
  // 0.8 %; the command held over each tick takes 0.3 % off it.
  std::printf("40 Hz sinusoid: amplitude ratio %.4f (-3 dB: %.4f)\n", peak / 10.0, 1.0 / std::sqrt(2.0));
  EXPECT_NEAR(peak / 10.0, 1.0 / std::sqrt(2.0), 0.05 / std::sqrt(2.0));
}

// The delivered torque moves at most rate_limit per second, and stays
// within the effort limit whatever the PD asks.
TEST(Actuator, RateLimitAndSaturation) {
  ActuatorParams a = loopOnly(60.0, 0.5);
  a.rate_limit = 2.0e4;
  JointActuator act(a, EncoderParams{}, 150.0);
  act.reset(0.0, -150.0);
  const double h = 1e-4;
  double worst_rate = 0.0, worst_torque = 0.0, reached = -1.0;
  for (int k = 0; k < 1000; ++k) {
    const double before = act.delivered();
    act.step(torque(1000.0), 0.0, 0.0, h);  // the PD's 1000 N m saturate at 150
    worst_rate = std::max(worst_rate, std::fabs(act.delivered() - before) / h);
    worst_torque = std::max(worst_torque, std::fabs(act.delivered()));
    if (reached < 0.0 && act.delivered() >= 149.999) reached = (k + 1) * h;
  }
  EXPECT_EQ(act.demanded(), 150.0);
  EXPECT_LE(worst_rate, 2.0e4 * (1.0 + 1e-9));
  EXPECT_LE(worst_torque, 150.0);
  // -150 to 150 N m at 2e4 N m/s takes at least 15 ms.
  EXPECT_GE(reached, 0.015 - 1e-9);
  // A command that is not finite asks for nothing.
  JointCommand bad = torque(NAN);
  EXPECT_EQ(act.pd(bad), 0.0);
}

// The valves' flow limit: along the joint's motion the delivered torque is
// at most effort (1 - (qd / limit)^2), none from the limit on; against the
// motion, or at rest, the whole effort limit; the sensor reads what is
// delivered; without a limit (0) the joint's speed changes nothing.
TEST(Actuator, FlowLimitTakesTheTorqueAlongTheMotionAway) {
  ActuatorParams a = loopOnly(60.0, 1.0 / std::sqrt(2.0));
  a.velocity_limit = 12.0;
  const double h = 1e-3;
  auto settled = [&](const ActuatorParams& params, double command, double qd) {
    JointActuator act(params, EncoderParams{}, 150.0);
    act.reset(0.0, 0.0);
    for (int k = 0; k < 500; ++k) act.step(torque(command), 0.0, qd, h);
    return act;
  };
  EXPECT_NEAR(settled(a, 140.0, 0.0).delivered(), 140.0, 1e-6);
  EXPECT_NEAR(settled(a, 140.0, 6.0).delivered(), 150.0 * (1.0 - 0.25), 1e-9);   // 112.5 N m
  EXPECT_NEAR(settled(a, -140.0, -6.0).delivered(), -112.5, 1e-9);
  EXPECT_NEAR(settled(a, 50.0, 6.0).delivered(), 50.0, 1e-6);                    // under the cap
  EXPECT_EQ(settled(a, 140.0, 12.0).delivered(), 0.0);
  EXPECT_EQ(settled(a, 140.0, 20.0).delivered(), 0.0);
  EXPECT_NEAR(settled(a, -140.0, 20.0).delivered(), -140.0, 1e-6);              // braking
  EXPECT_NEAR(settled(a, 140.0, 6.0).measured(), 112.5, 1e-6);
  ActuatorParams none = a;
  none.velocity_limit = 0.0;
  EXPECT_NEAR(settled(none, 140.0, 20.0).delivered(), 140.0, 1e-6);
}

// The torque sensor is the first-order filter of its cutoff applied to
// the delivered torque at each integration step: a filter written here
// reproduces it to rounding; at rest it reads what is delivered.
TEST(Actuator, TorqueSensorIsAFirstOrderFilterOfTheDeliveredTorque) {
  ActuatorParams a = loopOnly(40.0, 0.7);
  a.torque_sensor_cutoff = 25.0;
  JointActuator act(a, EncoderParams{}, 150.0);
  act.reset(0.0, 0.0);
  const double h = JointActuator::kMaxIntegrationStep;
  const double alpha = 1.0 - std::exp(-2.0 * kPi * 25.0 * h);
  double filtered = 0.0;
  for (int k = 0; k < 5000; ++k) {
    act.step(torque(k < 2500 ? 80.0 : -30.0), 0.0, 0.0, h);
    filtered += alpha * (act.delivered() - filtered);
    ASSERT_NEAR(act.measured(), filtered, 1e-9) << k;
  }
  EXPECT_NEAR(act.measured(), -30.0, 1e-6);
}

// The PD runs on the board's encoder sample: kp (q_ref - q) + kd (qd_ref -
// qd) with the encoder's reading, saturated.
TEST(Actuator, PdUsesTheBoardsEncoderReading) {
  EncoderParams e;
  e.resolution = 0.01;
  JointActuator act(loopOnly(40.0, 0.7), e, 150.0);
  act.reset(0.123, 0.0);  // reads 0.12
  JointCommand c;
  c.kp = 100.0;
  c.q_ref = 0.2;
  c.kd = 2.0;
  c.qd_ref = 1.0;
  EXPECT_NEAR(act.pd(c), 100.0 * (0.2 - 0.12) + 2.0 * 1.0, 1e-12);
}

// The PD samples the joint at its own rate: at 2 kHz twice in each 1 ms
// engine step (mid-step on the state extrapolated from the step's start),
// at 500 Hz once every second step. A joint turning at 1 rad/s under kp
// 100 N m/rad shows when: the PD's output is -100 x the sampled angle.
TEST(Actuator, PdRunsAtItsOwnRate) {
  for (double rate : {500.0, 1000.0, 2000.0}) {
    ActuatorParams a = loopOnly(40.0, 0.7);
    a.pd_rate = rate;
    JointActuator act(a, EncoderParams{}, 150.0);
    act.reset(0.0, 0.0);
    JointCommand c;
    c.kp = 100.0;
    const double h = 1e-3, v = 1.0;
    for (int k = 0; k < 20; ++k) {
      act.step(c, v * k * h, v, h);
      // The sample the step's PD last used: mid-step at 2 kHz, else the
      // latest on the PD's grid at or before the step's start.
      const double period = 1.0 / rate;
      const double last = rate > 1000.0 ? k * h + period : std::floor(k * h / period + 1e-9) * period;
      EXPECT_NEAR(act.demanded(), -100.0 * v * last, 1e-9) << rate << " Hz, step " << k;
      act.finishStep(v * (k + 1) * h, v);
    }
  }
}

// The encoder's reading is a whole number of its steps, the nearest one,
// and a slowly turning joint's reading changes by exactly one step at a time.
TEST(Encoder, QuantisesToItsStep) {
  const double step = kHyqEncoderResolution;
  EncoderParams e;
  e.resolution = step;
  JointEncoder enc(e);
  enc.reset(-0.3);
  double last = enc.position();
  int changes = 0;
  for (int k = 1; k <= 20000; ++k) {
    const double q = -0.3 + 1e-5 * k;  // slower than a step per sample
    enc.sample(q, 0.0, 1e-3);
    const double r = enc.position();
    EXPECT_LE(std::fabs(r - q), 0.5 * step + 1e-15);
    EXPECT_NEAR(r / step, std::round(r / step), 1e-9);
    if (r != last) {
      EXPECT_NEAR(std::fabs(r - last), step, 1e-12);
      ++changes;
    }
    last = r;
  }
  EXPECT_NEAR(changes, 0.2 / step, 2.0);  // 0.2 rad turned
}

// Under a steady acceleration the differentiated, filtered velocity lags
// the true one by its design lag T/2 + T/(exp(2 pi fc T) - 1): 1.644 ms at
// 100 Hz and 1 kHz (1/(2 pi fc) = 1.592 ms). Exactly without quantisation;
// with HyQ's encoder step, on average over a second.
TEST(Encoder, VelocityLagIsItsDesignLag) {
  const double fc = 100.0, period = 1e-3, accel = 20.0;  // [Hz], [s], [rad/s^2]
  const double lag = JointEncoder::velocityLag(fc, period);
  std::printf("velocity filter: lag %.4f ms (1/(2 pi fc) = %.4f ms)\n", 1e3 * lag, 1e3 / (2.0 * kPi * fc));
  EXPECT_NEAR(lag, 1.644e-3, 0.001e-3);
  for (double resolution : {0.0, kHyqEncoderResolution}) {
    EncoderParams e;
    e.resolution = resolution;
    e.velocity = VelocitySource::differentiated;
    e.velocity_cutoff = fc;
    JointEncoder enc(e);
    enc.reset(0.0);
    double lag_sum = 0.0, worst = 0.0;
    int n = 0;
    for (int k = 1; k <= 3000; ++k) {
      const double t = k * period;
      enc.sample(0.5 * accel * t * t, accel * t, period);
      if (t < 1.0) continue;  // the filter's start has died away (e^-628)
      const double measured_lag = t - enc.velocity() / accel;
      lag_sum += measured_lag;
      worst = std::max(worst, std::fabs(measured_lag - lag));
      ++n;
    }
    if (resolution == 0.0)
      EXPECT_LT(worst, 1e-9);
    else
      EXPECT_NEAR(lag_sum / n, lag, 0.05 * lag);
  }
}

// --- Transport delays, through the simulator with a command that does not
// depend on the sensors: the physics is the same whatever the sensors'
// delays, so frames can be compared tick by tick.

Scenario quietScenario() {
  Scenario s;
  s.name = "plant";
  s.duration = 1.0;
  s.sensors.noise = false;
  return s;
}

// Joint PD to the stand posture, and a feed-forward torque that changes
// every tick (so that each tick's command is recognisable).
hal::CommandFrame openLoopCommand(uint32_t tick) {
  hal::CommandFrame c{};
  c.tick = tick;
  for (int j = 0; j < 12; ++j) {
    c.q_ref[j] = robot::standAngle(j / 3, j % 3);
    c.kp[j] = 400.0;
    c.kd[j] = 6.0;
    c.tau_ff[j] = (j % 3 == 0 ? 0.0 : (j % 3 == 1 ? 5.0 : 40.0) * (robot::isFront(j / 3) ? -1.0 : 1.0)) *
                  (1.0 + 0.1 * std::sin(0.05 * tick));
  }
  return c;
}

struct Frames {
  std::vector<hal::SensorFrame> sensors;
  std::vector<std::array<double, 12>> applied;
};

Frames runOpenLoop(const Scenario& s, int ticks) {
  Simulator sim(s);
  Frames f;
  TickRecord rec;
  for (int k = 0; k < ticks; ++k) {
    f.sensors.push_back(sim.sensorFrame());
    sim.step(openLoopCommand(static_cast<uint32_t>(k)), rec);
    f.applied.push_back(rec.tau_applied);
  }
  return f;
}

TEST(Delays, SensorAndImuFramesAreExactlyNTicksOld) {
  const int ticks = 300;
  const Frames now = runOpenLoop(quietScenario(), ticks);
  for (const auto& [sensor_delay, imu_delay] : {std::pair{1, 0}, std::pair{3, 2}, std::pair{0, 4}}) {
    Scenario s = quietScenario();
    s.plant.delay.sensor_ticks = sensor_delay;
    s.plant.delay.imu_ticks = imu_delay;
    const Frames late = runOpenLoop(s, ticks);
    for (int k = 0; k < ticks; ++k) {
      const hal::SensorFrame& f = late.sensors[k];
      const hal::SensorFrame& joints = now.sensors[std::max(0, k - sensor_delay)];
      const hal::SensorFrame& imu = now.sensors[std::max(0, k - sensor_delay - imu_delay)];
      ASSERT_EQ(f.tick, static_cast<uint32_t>(k));
      for (int j = 0; j < 12; ++j) {
        ASSERT_EQ(f.q[j], joints.q[j]) << k;
        ASSERT_EQ(f.qd[j], joints.qd[j]) << k;
        ASSERT_EQ(f.tau[j], joints.tau[j]) << k;
      }
      for (int i = 0; i < 4; ++i) ASSERT_EQ(f.imu_quat[i], imu.imu_quat[i]) << k;
      for (int i = 0; i < 3; ++i) {
        ASSERT_EQ(f.imu_gyro[i], imu.imu_gyro[i]) << k;
        ASSERT_EQ(f.imu_acc[i], imu.imu_acc[i]) << k;
      }
    }
  }
}

// With the ideal joint loop and kp = kd = 0 the applied torque is the
// command's feed-forward: that of the command answered n ticks before (the
// first command until there was one n ticks old).
TEST(Delays, CommandsReachTheJointsExactlyNTicksLater) {
  for (int delay : {1, 2, 5}) {
    Scenario s = quietScenario();
    s.plant.delay.command_ticks = delay;
    Simulator sim(s);
    TickRecord rec;
    for (int k = 0; k < 50; ++k) {
      hal::CommandFrame c = openLoopCommand(static_cast<uint32_t>(k));
      for (int j = 0; j < 12; ++j) c.kp[j] = c.kd[j] = 0.0;
      sim.step(c, rec);
      const hal::CommandFrame sent = openLoopCommand(static_cast<uint32_t>(std::max(0, k - delay)));
      for (int j = 0; j < 12; ++j) ASSERT_EQ(rec.tau_applied[j], sent.tau_ff[j]) << "delay " << delay << " tick " << k;
      EXPECT_EQ(rec.command.tick, static_cast<uint32_t>(k));  // the record keeps the controller's answer
    }
  }
}

// --- The IMU where HyQ has it: its accelerometer feels the lever arm, and
// the driver turns its readings into B.
TEST(MountedImu, ReadsTheLeverArmInTheBaseFrame) {
  SensorSpec spec;
  spec.noise = false;
  PlantSpec plant;
  plant.imu = ImuMount::mounted;
  SensorModel mounted(spec, 1, plant), origin(spec, 1);
  TrueProprioception truth;
  truth.base_orientation = Quat(Eigen::AngleAxisd(0.4, Vec3(0.3, -0.5, 1.0).normalized()));
  truth.base_omega = Vec3(0.7, -1.1, 0.4);
  truth.base_alpha = Vec3(-3.0, 2.0, 5.0);
  truth.base_acceleration = Vec3(0.5, -0.2, 1.5);
  hal::SensorFrame at_mount{}, at_origin{};
  mounted.measure(7, truth, at_mount);
  origin.measure(7, truth, at_origin);
  const Mat3 r = truth.base_orientation.toRotationMatrix();
  const Vec3 lever = r * Vec3(0.290, 0.0, 0.0999);
  const Vec3 w = truth.base_omega;
  const Vec3 expected_acc = r.transpose() * (truth.base_acceleration + truth.base_alpha.cross(lever) +
                                             w.cross(w.cross(lever)) + Vec3(0.0, 0.0, robot::kGravity));
  const Vec3 expected_gyro = r.transpose() * w;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(at_mount.imu_acc[i], expected_acc[i], 1e-12);
    EXPECT_NEAR(at_mount.imu_gyro[i], expected_gyro[i], 1e-12);
    EXPECT_NEAR(at_mount.imu_gyro[i], at_origin.imu_gyro[i], 1e-12);
  }
  const Quat q(at_mount.imu_quat[0], at_mount.imu_quat[1], at_mount.imu_quat[2], at_mount.imu_quat[3]);
  EXPECT_NEAR(q.angularDistance(truth.base_orientation), 0.0, 1e-12);
  // The lever arm's part: what the origin's IMU does not read.
  const Vec3 origin_acc(at_origin.imu_acc[0], at_origin.imu_acc[1], at_origin.imu_acc[2]);
  EXPECT_GT((expected_acc - origin_acc).norm(), 0.5);
}

// summary.json names the plant that ran: the metrics take it from the
// simulator's records.
TEST(PlantSummary, NamesTheActuatorTheDelaysAndTheBody) {
  Scenario s = quietScenario();
  s.plant = hyqPlant();
  Simulator sim(s);
  Metrics metrics;
  TickRecord rec;
  for (int k = 0; k < 5; ++k) {
    sim.step(openLoopCommand(static_cast<uint32_t>(k)), rec);
    metrics.onTick(rec);
  }
  metrics.onFinish();
  std::string plant;
  for (const auto& [key, value] : metrics.summaryFields())
    if (key == "plant") plant = value;
  for (const char* part : {"\"model\": \"hyq\"", "\"model\": \"second_order_torque_loop\"", "\"bandwidth_hz\": 40",
                           "\"velocity_limit_rad_per_s\": 12}",
                           "\"delay_ticks\": {\"sensor\": 1, \"command\": 1, \"imu\": 2}",
                           "\"velocity\": \"differentiated\"", "\"imu\": \"mounted\"", "\"body\": \"published\""})
    EXPECT_NE(plant.find(part), std::string::npos) << part << " in " << plant;
}

// --- Scenario keys
// A file that names no plant runs on the hyq plant, unless its reader is
// asked for the ideal one.
TEST(PlantKeys, HyqIsTheDefaultAndSetsEveryPart) {
  const std::string head = "name: p\nduration: 1\n";
  EXPECT_EQ(parseScenario(head, "none.yaml").plant.model, PlantModel::hyq);
  EXPECT_TRUE(parseScenario(head, "none.yaml", PlantModel::ideal).plant.isIdeal());
  EXPECT_TRUE(parseScenario(head + "plant: {model: ideal}\n", "ideal.yaml").plant.isIdeal());
  EXPECT_EQ(parseScenario(head + "plant: {model: hyq}\n", "hyq.yaml", PlantModel::ideal).plant.model, PlantModel::hyq);
  const PlantSpec hyq = parseScenario(head, "hyq.yaml").plant;
  EXPECT_EQ(hyq.model, PlantModel::hyq);
  EXPECT_TRUE(hyq.actuator.model);
  EXPECT_EQ(hyq.actuator.pd_rate, 1000.0);
  EXPECT_EQ(hyq.actuator.bandwidth, 40.0);
  EXPECT_EQ(hyq.actuator.velocity_limit, 12.0);
  EXPECT_EQ(hyq.encoder.resolution, kHyqEncoderResolution);
  EXPECT_EQ(hyq.encoder.velocity, VelocitySource::differentiated);
  EXPECT_EQ(hyq.delay.sensor_ticks, 1);
  EXPECT_EQ(hyq.delay.command_ticks, 1);
  EXPECT_EQ(hyq.delay.imu_ticks, 2);
  EXPECT_EQ(hyq.body, BodyModel::published);
  EXPECT_EQ(hyq.imu, ImuMount::mounted);
  // A part's own key over the preset.
  const PlantSpec mixed = parseScenario(head +
                                            "plant:\n  model: hyq\n  body: nominal\n"
                                            "  actuator: {bandwidth: 60, velocity_limit: 0}\n  delay: {command_ticks: 0}\n",
                                        "mixed.yaml")
                              .plant;
  EXPECT_EQ(mixed.body, BodyModel::nominal);
  EXPECT_EQ(mixed.actuator.bandwidth, 60.0);
  EXPECT_EQ(mixed.actuator.velocity_limit, 0.0);
  EXPECT_EQ(mixed.delay.command_ticks, 0);
  EXPECT_EQ(mixed.delay.sensor_ticks, 1);
}

// The hyq plant configures the controller for HyQ's 40 Hz torque loop
// unless the scenario sets it; the ideal plant leaves ideal joints (0).
// Likewise the crawl's shift bound (kHyqShiftAcceleration).
TEST(PlantKeys, HyqConfiguresTheControllersTorqueBandwidth) {
  const std::string head = "name: p\nduration: 1\n";
  const std::string ideal = head + "plant: {model: ideal}\n";
  EXPECT_EQ(parseScenario(ideal, "ideal.yaml").controller_params.joint.torque_bandwidth, 0.0);
  EXPECT_EQ(parseScenario(head, "none.yaml", PlantModel::ideal).controller_params.joint.torque_bandwidth, 0.0);
  EXPECT_EQ(parseScenario(head, "none.yaml").controller_params.joint.torque_bandwidth,
            kHyqControllerTorqueBandwidth);
  EXPECT_EQ(parseScenario(head + "plant: {model: hyq}\n", "hyq.yaml").controller_params.joint.torque_bandwidth,
            kHyqControllerTorqueBandwidth);
  // The plant's own bandwidth does not move the controller's.
  EXPECT_EQ(parseScenario(head + "plant: {model: hyq, actuator: {bandwidth: 10}}\n", "hyq10.yaml")
                .controller_params.joint.torque_bandwidth,
            40.0);
  const Scenario set = parseScenario(head +
                                         "plant: {model: hyq}\n"
                                         "controller: {joint: {torque_bandwidth: 0, swing_kd: 5}, slip_damping: 60}\n",
                                     "set.yaml");
  EXPECT_EQ(set.controller_params.joint.torque_bandwidth, 0.0);
  EXPECT_EQ(set.controller_params.joint.swing_kd, 5.0);
  EXPECT_EQ(set.controller_params.recovery.slip_damping, 60.0);
  // And the crawl's body shift bounded, unless the scenario sets the bound.
  EXPECT_EQ(parseScenario(ideal, "ideal.yaml").controller_params.gait.max_shift_acceleration, 0.0);
  EXPECT_EQ(parseScenario(head + "plant: {model: hyq}\n", "hyq.yaml").controller_params.gait.max_shift_acceleration,
            kHyqShiftAcceleration);
  EXPECT_EQ(parseScenario(head + "plant: {model: hyq}\ngait: {max_shift_acceleration: 0}\n", "off.yaml")
                .controller_params.gait.max_shift_acceleration,
            0.0);
  // The trot's duty factor and guess delay likewise (kHyqTrotDutyFactor,
  // kHyqTrotGuessDelay).
  struct TrotPreset {
    const char* key;
    double TrotParams::*member;
    double hyq, own;
  };
  for (const TrotPreset& p : {TrotPreset{"duty_factor", &TrotParams::duty_factor, kHyqTrotDutyFactor, 0.6},
                              TrotPreset{"guess_delay", &TrotParams::guess_delay, kHyqTrotGuessDelay, 0.05}}) {
    EXPECT_EQ(parseScenario(ideal, "ideal.yaml").controller_params.gait.trot.*p.member, TrotParams{}.*p.member)
        << p.key;
    EXPECT_EQ(parseScenario(head + "plant: {model: hyq}\n", "hyq.yaml").controller_params.gait.trot.*p.member, p.hyq)
        << p.key;
    const std::string own = head + "plant: {model: hyq}\ngait: {trot: {" + p.key + ": " + std::to_string(p.own) + "}}\n";
    EXPECT_EQ(parseScenario(own, "own.yaml").controller_params.gait.trot.*p.member, p.own) << p.key;
  }
  // And the crawl's step height (kHyqCrawlStepHeight), but the trot's own.
  EXPECT_EQ(parseScenario(ideal, "ideal.yaml").controller_params.gait.step_height, GaitParams{}.step_height);
  const Scenario low = parseScenario(head + "plant: {model: hyq}\n", "hyq.yaml");
  EXPECT_EQ(low.controller_params.gait.step_height, kHyqCrawlStepHeight);
  EXPECT_EQ(low.controller_params.gait.trot.step_height, TrotParams{}.step_height);
  EXPECT_EQ(parseScenario(head + "plant: {model: hyq}\ngait: {step_height: 0.1}\n", "own.yaml")
                .controller_params.gait.step_height,
            0.1);
  const Scenario scaled = parseScenario(head + "plant: {trunk_mass_scale: 1.2, trunk_inertia_scale: 0.9}\n", "s.yaml");
  EXPECT_EQ(scaled.plant.trunk_mass_scale, 1.2);
  EXPECT_EQ(scaled.plant.trunk_inertia_scale, 0.9);
  EXPECT_FALSE(scaled.plant.isIdeal());
}

// An IMU mounted where HyQ has it is where the controller takes its lever
// arm out, on any plant, unless the scenario says otherwise; at the origin
// there is none to take out.
TEST(PlantKeys, AMountedImuIsWhereTheControllerTakesItsLeverArmOut) {
  const std::string head = "name: p\nduration: 1\n";
  auto position = [&](const std::string& body) {
    const Scenario s = parseScenario(head + body, "imu.yaml");
    const double* r = s.controller_params.estimator.imu_position;
    return std::array<double, 3>{r[0], r[1], r[2]};
  };
  const std::array<double, 3> none{0.0, 0.0, 0.0}, mount{0.290, 0.0, 0.0999};
  EXPECT_EQ(position(""), mount);
  EXPECT_EQ(position("plant: {model: ideal}\n"), none);
  EXPECT_EQ(position("plant: {model: hyq}\n"), mount);
  EXPECT_EQ(position("plant: {model: hyq, imu: origin}\n"), none);
  EXPECT_EQ(position("plant: {model: ideal, imu: mounted}\n"), mount);
  EXPECT_EQ(position("plant: {model: hyq}\ncontroller: {estimator: {imu_position: [0, 0, 0]}}\n"), none);
  EXPECT_EQ(position("plant: {model: hyq}\ncontroller: {estimator: {imu_position: [0.1, 0, 0]}}\n"),
            (std::array<double, 3>{0.1, 0.0, 0.0}));
}

// putOnHyqPlant configures the controller as `plant: {model: hyq}` does.
TEST(PlantKeys, PutOnHyqPlantConfiguresTheControllerAsTheKeyDoes) {
  const std::string head = "name: p\nduration: 1\n";
  Scenario put = parseScenario(head, "none.yaml", PlantModel::ideal);
  putOnHyqPlant(put);
  const Scenario parsed = parseScenario(head + "plant: {model: hyq}\n", "hyq.yaml");
  EXPECT_EQ(put.controller_params.joint.torque_bandwidth, parsed.controller_params.joint.torque_bandwidth);
  EXPECT_EQ(put.controller_params.gait.max_shift_acceleration, parsed.controller_params.gait.max_shift_acceleration);
  EXPECT_EQ(put.controller_params.gait.trot.duty_factor, parsed.controller_params.gait.trot.duty_factor);
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(put.controller_params.estimator.imu_position[k], parsed.controller_params.estimator.imu_position[k]);
  EXPECT_EQ(put.plant.model, PlantModel::hyq);
  EXPECT_EQ(put.plant.imu, parsed.plant.imu);
  EXPECT_EQ(put.plant.body, parsed.plant.body);
  EXPECT_EQ(put.plant.delay.command_ticks, parsed.plant.delay.command_ticks);
}

TEST(PlantKeys, OutOfRangeAndUnknownValuesAreRefusedByName) {
  const std::string head = "name: p\nduration: 1\nplant:\n";
  auto refused = [&](const std::string& body, const std::string& needle) {
    try {
      parseScenario(head + body, "bad.yaml");
    } catch (const ScenarioError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "accepted: " << body;
  };
  refused("  model: real\n", "plant.model");
  refused("  actuator: {bandwidth: 0.5}\n", "plant.actuator.bandwidth: out of range");
  refused("  actuator: {pd_rate: 20000}\n", "plant.actuator.pd_rate: out of range");
  refused("  actuator: {model: fast}\n", "plant.actuator.model");
  refused("  actuator: {velocity_limit: -1}\n", "plant.actuator.velocity_limit: out of range");
  refused("  encoder: {resolution: -1e-4}\n", "plant.encoder.resolution: out of range");
  refused("  encoder: {velocity: guessed}\n", "plant.encoder.velocity");
  refused("  delay: {sensor_ticks: 11}\n", "plant.delay.sensor_ticks: out of range");
  refused("  trunk_mass_scale: 0.4\n", "plant.trunk_mass_scale: out of range");
  refused("  trunk_inertia_scale: 2.5\n", "plant.trunk_inertia_scale: out of range");
  refused("  delay: {imu_ticks: 1.5}\n", "plant.delay.imu_ticks: expected an integer");
  refused("  body: heavy\n", "plant.body");
  refused("  imu: sideways\n", "plant.imu");
  refused("  valves: 3\n", "unknown key");
}

}  // namespace
}  // namespace hyq::sim
