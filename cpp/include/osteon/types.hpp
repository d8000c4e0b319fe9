// Basic types shared by the osteon engine. Units: millimetres, newtons, MPa (N/mm^2).
#pragma once

#include <Eigen/Dense>
#include <cstdint>

namespace osteon {

using Index = std::int64_t;
using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;

}  // namespace osteon
