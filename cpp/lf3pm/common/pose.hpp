// A rigid sensor-to-world pose.
#pragma once

#include <Eigen/Core>

namespace lf3pm {

struct Pose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // sensor -> world
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

}  // namespace lf3pm
