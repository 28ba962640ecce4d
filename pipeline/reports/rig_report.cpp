// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/rig_report.hpp"

#include <cmath>
#include <cstdio>

#include "common/number_text.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
namespace {

std::array<double, 9> flat(const Eigen::Matrix3d& c) {
  std::array<double, 9> out{};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) out[static_cast<std::size_t>(3 * r + k)] = c(r, k);
  return out;
}

double se(const std::array<double, 9>& c, int i) {
  return std::sqrt(std::max(0.0, c[static_cast<std::size_t>(4 * i)]));
}

/// One sensor's range model as a single-sensor model.json holds it.
CalibrationModel sensorModel(const io::Rig& rig, std::size_t k, const calibration::RigResult& r) {
  const calibration::RigSensorEstimate& e = r.sensors[k];
  CalibrationModel m;
  m.method = "rig-joint";
  m.sensor_name = rig.sequences[k].meta.sensor_name.value_or(rig.meta.sensors[k].name);
  m.model = e.model;
  m.order_rule = "bic";
  for (const auto& [order, bic] : e.order_bic) {
    OrderRow row;
    row.order = order;
    row.bic = bic;
    row.aic = std::nan("");
    row.validation_mse_m2 = row.test_mse_m2 = std::nan("");
    m.orders.push_back(row);
  }
  const auto n = static_cast<std::size_t>(e.alpha_covariance.rows());
  for (std::size_t i = 0; i < n * n; ++i)
    m.alpha_covariance.push_back(e.alpha_covariance(i / n, i % n));
  m.fitted_range_m = std::make_pair(e.d_min_m, e.d_max_m);
  m.status = e.model_status;
  m.iterations = r.solver_iterations;
  m.residual_rms_m = e.residual_rms_m;
  m.readings = e.readings;
  m.motion_prior = r.motion_prior;
  m.stop_poses = r.vehicle;
  return m;
}

/// The design and the difference (mm, deg; the design is exact, so the estimate's standard errors).
std::string designCells(const Pose2& estimate, const std::optional<Pose2>& design,
                        const std::array<double, 9>& c) {
  if (!design) return " none | - |\n";
  return formatted(" %.4f, %.4f, %.2f | %+.1f +- %.1f, %+.1f +- %.1f, %+.2f +- %.2f |\n",
                   design->x_m, design->y_m, rad2deg(design->yaw_rad),
                   1000.0 * (estimate.x_m - design->x_m), 1000.0 * se(c, 0),
                   1000.0 * (estimate.y_m - design->y_m), 1000.0 * se(c, 1),
                   rad2deg(wrapAngle(estimate.yaw_rad - design->yaw_rad)), rad2deg(se(c, 2)));
}

/// "front and back", "a, b and c".
std::string listed(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  return out;
}

/// The caution printed right above the lines to paste when a range model was refused: the
/// mountings were fitted together with those models, and how far each lies from its design.
std::string refusedModelsCaution(const io::RigModel& m) {
  std::vector<std::string> refused, offsets;
  for (const io::RigModelSensor& s : m.sensors) {
    if (!s.model.status.ok()) refused.push_back(s.name);
    if (s.mounting_held) {
      offsets.push_back(s.name + " is held at its design");
    } else if (s.design) {
      const double dx = s.mounting.x_m - s.design->x_m, dy = s.mounting.y_m - s.design->y_m;
      offsets.push_back(
          formatted("%s lies %.0f mm from its design (x %+.0f mm, y %+.0f mm, yaw %+.2f deg)",
                    s.name.c_str(), 1000.0 * std::hypot(dx, dy), 1000.0 * dx, 1000.0 * dy,
                    rad2deg(wrapAngle(s.mounting.yaw_rad - s.design->yaw_rad))));
    }
  }
  if (refused.empty()) return {};
  return "caution: these mountings rest on range models that were refused (" + listed(refused) +
         ": see the status above), fitted together with them; " +
         (offsets.empty() ? std::string("no design to compare them with") : listed(offsets)) +
         ". Check them against a tape before pasting, or calibrate again with data that "
         "determine the range models.\n";
}

}  // namespace

io::RigModel rigModel(const io::Rig& rig, const calibration::RigResult& r) {
  io::RigModel m;
  m.frame = toString(r.frame);
  m.reference = rig.meta.sensors[r.reference].name;
  m.vehicle_frame = rig.meta.vehicle_frame;
  m.scale_free = r.scale_free;
  m.motion_prior = r.motion_prior;
  m.radius_m = r.radius_m;
  for (std::size_t k = 0; k < r.sensors.size(); ++k) {
    const io::RigSensorInfo& info = rig.meta.sensors[k];
    io::RigModelSensor s{info.name,
                         info.topic,
                         info.frame_id,
                         r.sensors[k].mounting,
                         flat(r.sensors[k].mounting_covariance),
                         r.sensors[k].mounting_held,
                         info.mounting,
                         r.sensors[k].beam_scatter_m,
                         sensorModel(rig, k, r)};
    m.sensors.push_back(std::move(s));
  }
  for (const calibration::RigRelativeMounting& rel : r.relative) {
    io::RigModelRelative out{m.sensors[rel.reference].name, m.sensors[rel.sensor].name, rel.pose,
                             flat(rel.covariance), std::nullopt};
    if (m.sensors[rel.reference].design && m.sensors[rel.sensor].design)
      out.design =
          relativeMounting(*m.sensors[rel.reference].design, *m.sensors[rel.sensor].design);
    m.relative.push_back(out);
  }
  for (const calibration::RigPoleEstimate& p : r.poles) {
    io::RigModelPole pole{
        p.id,
        p.x_m,
        p.y_m,
        {p.covariance(0, 0), p.covariance(0, 1), p.covariance(1, 0), p.covariance(1, 1)},
        {}};
    for (const std::size_t k : p.sensors) pole.sensors.push_back(m.sensors[k].name);
    m.poles.push_back(pole);
  }
  m.stops = r.vehicle;
  m.notes = r.notes;
  m.status = r.status;
  return m;
}

std::string rigMountingTable(const io::RigModel& m) {
  std::string t = formatted(
      "mountings in %s (%s frame%s), +- one standard error\n",
      m.vehicle_frame.empty() ? "the vehicle frame" : m.vehicle_frame.c_str(), m.frame.c_str(),
      m.frame == "relative" ? (", " + m.reference + " held at its design").c_str() : "");
  t += "| sensor | x (m) | y (m) | yaw (deg) | flip | design x, y (m), yaw (deg) | difference x, y "
       "(mm), yaw (deg) |\n"
       "|---|---|---|---|---|---|---|\n";
  for (const io::RigModelSensor& s : m.sensors) {
    const auto& c = s.mounting_covariance;
    t += formatted("| %s | %.4f +- %.4f | %.4f +- %.4f | %.2f +- %.2f | %s |", s.name.c_str(),
                   s.mounting.x_m, se(c, 0), s.mounting.y_m, se(c, 1), rad2deg(s.mounting.yaw_rad),
                   rad2deg(se(c, 2)), s.mounting.upside_down ? "upside down" : "upright");
    t += designCells(s.mounting.pose(),
                     s.design ? std::optional<Pose2>(s.design->pose()) : std::nullopt, c);
  }
  if (!m.relative.empty())
    t += "\n| sensor in reference's frame | x (m) | y (m) | yaw (deg) | tf_static x, y (m), yaw "
         "(deg) | difference x, y (mm), yaw (deg) |\n"
         "|---|---|---|---|---|---|\n";
  for (const io::RigModelRelative& r : m.relative) {
    const auto& c = r.covariance;
    t += formatted("| %s in %s | %.4f +- %.4f | %.4f +- %.4f | %.2f +- %.2f |", r.sensor.c_str(),
                   r.reference.c_str(), r.pose.x_m, se(c, 0), r.pose.y_m, se(c, 1),
                   rad2deg(r.pose.yaw_rad), rad2deg(se(c, 2)));
    t += designCells(r.pose, r.design, c);
  }
  t += "\n| sensor | range model f(d) | noise | beams' repeating error (mm) | status "
       "|\n|---|---|---|---|---|\n";
  for (const io::RigModelSensor& s : m.sensors) {
    std::string f;
    const auto& a = s.model.model.bias.alpha;
    const std::size_t n = a.size();
    for (std::size_t i = 0; i < n; ++i) {
      const double sd = s.model.alpha_covariance.size() == n * n
                            ? std::sqrt(std::max(0.0, s.model.alpha_covariance[i * n + i]))
                            : 0.0;
      f += formatted("%salpha_%zu %.5f +- %.5f", i ? ", " : "", i, a[i], sd);
    }
    t += formatted("| %s | %s | %s | %.1f | %s |\n", s.name.c_str(), f.c_str(),
                   toString(s.model.model.noise.kind), 1000.0 * s.beam_scatter_m,
                   s.model.status.ok() ? "ok" : s.model.status.message.c_str());
  }
  return t;
}

std::string rigSnippets(const io::RigModel& m) {
  const std::string parent = m.vehicle_frame.empty() ? "base_link" : m.vehicle_frame;
  std::string launch, urdf;
  for (const io::RigModelSensor& s : m.sensors) {
    const std::string child = s.frame_id.empty() ? s.name : s.frame_id;
    const double z = s.design ? s.design->z_m : s.mounting.z_m;
    const double roll = s.mounting.upside_down ? M_PI : 0.0;
    // static_transform_publisher x y z yaw pitch roll parent child (ZYX Euler): roll pi turns the
    // sensor over about its x axis, which keeps the heading of that axis.
    launch += formatted(
        "rosrun tf2_ros static_transform_publisher %.4f %.4f %.4f %.5f 0 %.5f %s %s\n",
        s.mounting.x_m, s.mounting.y_m, z, s.mounting.yaw_rad, roll, parent.c_str(), child.c_str());
    urdf += formatted(
        "<joint name=\"%s_joint\" type=\"fixed\"><parent link=\"%s\"/><child link=\"%s\"/>"
        "<origin xyz=\"%.4f %.4f %.4f\" rpy=\"%.5f 0 %.5f\"/></joint>\n",
        child.c_str(), parent.c_str(), child.c_str(), s.mounting.x_m, s.mounting.y_m, z, roll,
        s.mounting.yaw_rad);
  }
  return "tf_static with the estimated mountings (z from the design):\n" + refusedModelsCaution(m) +
         launch + urdf;
}

}  // namespace lidarcal::pipeline
