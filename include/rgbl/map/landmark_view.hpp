#pragma once
// The visibility test shared by everything that projects map landmarks into a camera (the tracker's
// local-map search, landmark fusion): header-only, it runs for every local landmark of every frame.

#include "rgbl/geometry/camera.hpp"
#include "rgbl/map/map.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>

namespace rgbl {

// How a landmark appears to a camera.
struct LandmarkView {
  Eigen::Vector3d p_cam = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  double distance = 0.0;  // from the camera centre
  int level = 0;          // pyramid level its keypoint should appear on at that distance
};

// The landmark seen by a camera at T_cam_world (centre = its position in the world), or nullopt when
// it cannot be: behind the camera, outside the image, outside 0.8x-1.2x the distances it was observed
// from (scale invariance of ORB), or more than acos(min_view_cos) off its mean viewing direction.
inline std::optional<LandmarkView> view_landmark(const Landmark& landmark, const Eigen::Isometry3d& T_cam_world,
                                                 const Eigen::Vector3d& center, const PinholeCamera& camera,
                                                 const MapOptions& map_options, double min_view_cos) {
  LandmarkView view;
  view.p_cam = T_cam_world * landmark.position;
  if (view.p_cam.z() <= 0.0) return std::nullopt;
  view.pixel = camera.project_unchecked(view.p_cam);
  if (!camera.in_image(view.pixel)) return std::nullopt;
  const Eigen::Vector3d ray = landmark.position - center;
  view.distance = ray.norm();
  if (view.distance < 0.8 * landmark.min_distance || view.distance > 1.2 * landmark.max_distance) return std::nullopt;
  if (ray.dot(landmark.normal) < min_view_cos * view.distance) return std::nullopt;
  view.level = landmark.predict_level(view.distance, map_options.levels, map_options.scale_factor);
  return view;
}

}  // namespace rgbl
