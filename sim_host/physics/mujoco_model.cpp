#include "sim_host/physics/mujoco_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/physics/body_model.hpp"

namespace hyq::sim {
namespace {
using namespace hyq::robot;

// MuJoCo's least friction coefficient; a mu 0 patch is given this.
constexpr double kMinMu = 1e-5;

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

std::string vec(double a, double b, double c) { return num(a) + " " + num(b) + " " + num(c); }

// A solid cylinder along z: the inertia the ODE model gives each link.
std::string cylinderInertial(double mass, double length) {
  const double r = kLinkInertiaRadius;
  const double perp = mass * (3.0 * r * r + length * length) / 12.0;
  const double axial = 0.5 * mass * r * r;
  return "<inertial pos=\"" + vec(0, 0, -0.5 * length) + "\" mass=\"" + num(mass) +
         "\" diaginertia=\"" + vec(perp, perp, axial) + "\"/>";
}

// A link's inertial element from the body description (the nominal body's
// links are the solid cylinders).
std::string linkInertial(const RobotBody& body, int leg, int link, double length) {
  const LinkInertial& l = body.links[leg][link];
  if (body.cylinder_links) return cylinderInertial(l.mass, length);
  const Mat3& i = l.inertia;
  return "<inertial pos=\"" + vec(l.com.x(), l.com.y(), l.com.z()) + "\" mass=\"" + num(l.mass) +
         "\" fullinertia=\"" + vec(i(0, 0), i(1, 1), i(2, 2)) + " " + vec(i(0, 1), i(0, 2), i(1, 2)) + "\"/>";
}

std::string legXml(int leg, const std::string& contact, const RobotBody& body) {
  const std::string n = kLegNames[leg];
  const double lengths[3] = {kHipLength, kUpperLength, kLowerLength};
  const char* link[3] = {"hip", "upper", "lower"};
  const char* joint[3] = {"haa", "hfe", "kfe"};
  const std::string axis[3] = {vec(kHaaAxisSign[leg], 0, 0), vec(0, 1, 0), vec(0, 1, 0)};
  const std::string pos[3] = {vec(kHaaPos[leg][0], kHaaPos[leg][1], kHaaPos[leg][2]),
                              vec(0, 0, -kHipLength), vec(0, 0, -kUpperLength)};
  std::string x;
  for (int k = 0; k < 3; ++k) {
    double lo, hi;
    jointLimits(leg, k, lo, hi);
    x += "<body name=\"" + n + "_" + link[k] + "\" pos=\"" + pos[k] + "\">\n";
    x += "<joint name=\"" + n + "_" + joint[k] + "\" type=\"hinge\" axis=\"" + axis[k] +
         "\" limited=\"true\" range=\"" + num(lo) + " " + num(hi) + "\"/>\n";
    x += linkInertial(body, leg, k, lengths[k]) + "\n";
  }
  x += "<geom name=\"" + n + "_foot\" type=\"sphere\" size=\"" + num(kFootRadius) + "\" pos=\"" +
       vec(0, 0, -body.lower_length) + "\" " + contact + "/>\n";
  x += "</body>\n</body>\n</body>\n";
  return x;
}

// The friction at (x, y) before the first change and after each of the
// terrain's friction changes (timed patches): equal timelines, equal ground.
std::vector<double> muTimeline(const Terrain& terrain, double x, double y) {
  const std::vector<double>& changes = terrain.frictionChanges();
  std::vector<double> mu = {terrain.muAt(x, y, -std::numeric_limits<double>::infinity())};
  for (double t : changes) mu.push_back(terrain.muAt(x, y, t));
  return mu;
}

// The ground: for each straight piece of the profile, boxes over the
// cells between consecutive patch edges in x and in y, each with the
// friction the terrain gives the cell's middle at time 0 (neighbouring
// cells of equal friction at all times merged along y).
// `box(piece, x0, x1, y0, y1, mu, ym)` for each, ym the middle of its first
// cell along y; returns their count.
template <typename Box>
size_t forEachGroundBox(const Terrain& terrain, Box box) {
  const TerrainSpec& spec = terrain.spec();
  std::vector<double> ys = {-Terrain::kWorldHalfExtent, Terrain::kWorldHalfExtent};
  for (const FrictionPatch& p : spec.patches) ys.insert(ys.end(), {p.y0, p.y1});
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  size_t count = 0;
  for (const Terrain::Piece& piece : terrain.pieces()) {
    std::vector<double> xs = {piece.x_begin, piece.x_end};
    for (const FrictionPatch& p : spec.patches)
      for (double e : {p.x0, p.x1})
        if (e > piece.x_begin && e < piece.x_end) xs.push_back(e);
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
    for (size_t i = 0; i + 1 < xs.size(); ++i) {
      const double x0 = xs[i], x1 = xs[i + 1];
      if (x1 - x0 < 1e-9) continue;
      const double xm = 0.5 * (x0 + x1);
      for (size_t j = 0; j + 1 < ys.size();) {
        const std::vector<double> mu = muTimeline(terrain, xm, 0.5 * (ys[j] + ys[j + 1]));
        size_t e = j + 1;
        while (e + 1 < ys.size() && muTimeline(terrain, xm, 0.5 * (ys[e] + ys[e + 1])) == mu) ++e;
        const double ym = 0.5 * (ys[j] + ys[j + 1]);  // inside the first cell, off every edge
        box(piece, x0, x1, ys[j], ys[e], terrain.muAt(xm, ym, 0.0), ym);
        ++count;
        j = e;
      }
    }
  }
  return count;
}

std::string groundXml(const Terrain& terrain, const std::string& contact) {
  std::string x;
  int k = 0;
  forEachGroundBox(terrain, [&](const Terrain::Piece& piece, double x0, double x1, double y0,
                                double y1, double mu, double) {
    const double slope = (piece.z_end - piece.z_begin) / (piece.x_end - piece.x_begin);
    const double angle = std::atan(slope);
    const double c = std::cos(angle), s = std::sin(angle);
    const double xm = 0.5 * (x0 + x1);
    const double half_len = 0.5 * (x1 - x0) / c;
    const double zm = piece.z_begin + slope * (xm - piece.x_begin);
    const double h = 0.5 * Terrain::kBoxThickness;
    // Rotation about +y by -angle: x onto the piece's direction, z onto its
    // normal (-s, 0, c); the box's top face is the surface, its centre h
    // below it along the normal.
    x += "<geom name=\"ground_" + std::to_string(k++) + "\" type=\"box\" pos=\"" +
         vec(xm + h * s, 0.5 * (y0 + y1), zm - h * c) + "\" quat=\"" +
         num(std::cos(-0.5 * angle)) + " 0 " + num(std::sin(-0.5 * angle)) + " 0\" size=\"" +
         vec(half_len, 0.5 * (y1 - y0), h) + "\" friction=\"" + num(mujocoFriction(mu)) +
         " 0 0\" " + contact + " contype=\"0\" conaffinity=\"1\" priority=\"1\"/>\n";
  });
  return x;
}
}  // namespace

std::vector<TimedGroundBox> timedGroundBoxes(const Terrain& terrain) {
  std::vector<TimedGroundBox> timed;
  int k = 0;
  forEachGroundBox(terrain, [&](const Terrain::Piece&, double x0, double x1, double, double, double,
                                double y) {
    const double x = 0.5 * (x0 + x1);
    const std::vector<double> mu = muTimeline(terrain, x, y);
    if (std::adjacent_find(mu.begin(), mu.end(), std::not_equal_to<>()) != mu.end())
      timed.push_back({"ground_" + std::to_string(k), x, y});
    ++k;
  });
  return timed;
}

double mujocoFriction(double mu) { return std::max(mu, kMinMu); }

size_t mujocoGroundBoxes(const Terrain& terrain) {
  return forEachGroundBox(terrain, [](const Terrain::Piece&, double, double, double, double, double, double) {});
}

void checkMujocoGround(const Scenario& scenario, const Terrain& terrain) {
  const size_t boxes = mujocoGroundBoxes(terrain);
  if (boxes <= kMaxMujocoGroundBoxes) return;
  throw ScenarioError(clipForMessage(scenario.source_file.empty() ? "scenario" : scenario.source_file, 200) +
                      ": terrain.patches: the MuJoCo ground would need " + std::to_string(boxes) +
                      " boxes (one per piece of the profile and region of constant friction): at most " +
                      std::to_string(kMaxMujocoGroundBoxes));
}

std::string hyqMjcf(const Scenario& scenario, const Terrain& terrain, double timestep) {
  checkMujocoGround(scenario, terrain);
  const MujocoParams& mj = scenario.physics.mujoco;
  const std::string contact = "condim=\"3\" solref=\"" + num(mj.timeconst) + " " +
                              num(mj.dampratio) + "\" solimp=\"" +
                              vec(mj.solimp_d0, mj.solimp_dwidth, mj.solimp_width) + "\"";
  // The trunk's inertia about its centre of mass, with the payload spread
  // uniformly over the trunk box around that centre (as in the ODE model).
  const RobotBody body = plantBody(scenario.plant);
  const Mat3& ti = body.trunk_inertia;
  const double pm = scenario.payload_kg;
  const double sx = kTrunkSize[0], sy = kTrunkSize[1], sz = kTrunkSize[2];
  const double ixx = ti(0, 0) + pm * (sy * sy + sz * sz) / 12.0;
  const double iyy = ti(1, 1) + pm * (sx * sx + sz * sz) / 12.0;
  const double izz = ti(2, 2) + pm * (sx * sx + sy * sy) / 12.0;

  std::string x = "<mujoco model=\"hyq\">\n";
  x += "<compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n";
  x += "<option timestep=\"" + num(timestep) + "\" gravity=\"0 0 " + num(-kGravity) +
       "\" integrator=\"Euler\" cone=\"elliptic\" solver=\"Newton\" impratio=\"" +
       num(mj.impratio) + "\" noslip_iterations=\"" + std::to_string(mj.noslip_iterations) +
       "\" iterations=\"" + std::to_string(mj.solver_iterations) + "\" tolerance=\"" +
       num(mj.solver_tolerance) + "\"/>\n";
  // Room for a fall: the trunk box on many small ground boxes.
  x += "<size njmax=\"2000\" nconmax=\"500\"/>\n";
  x += "<worldbody>\n";
  x += groundXml(terrain, contact);
  x += "<body name=\"trunk\" pos=\"0 0 1\">\n<freejoint name=\"base\"/>\n";
  const Vec3& com = body.trunk_com;
  x += "<inertial pos=\"" + vec(com.x(), com.y(), com.z()) + "\" mass=\"" + num(body.trunk_mass + pm) +
       "\" fullinertia=\"" + vec(ixx, iyy, izz) + " " + vec(ti(0, 1), ti(0, 2), ti(1, 2)) + "\"/>\n";
  // The trunk meets the ground only in a fall.
  x += "<geom name=\"trunk_box\" type=\"box\" size=\"" + vec(0.5 * sx, 0.5 * sy, 0.5 * sz) +
       "\" friction=\"" + num(kMinMu) + " 0 0\" " + contact + " contype=\"1\" conaffinity=\"0\"/>\n";
  for (int leg = 0; leg < kNumLegs; ++leg)
    x += legXml(leg, "friction=\"" + num(kMinMu) + " 0 0\" " + contact + " contype=\"1\" conaffinity=\"0\"",
                body);
  x += "</body>\n</worldbody>\n</mujoco>\n";
  return x;
}

}  // namespace hyq::sim
