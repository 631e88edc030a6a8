#pragma once
// Geometry types: glm for small vectors (double for directions and precomputation, float for
// mesh data and runtime), Eigen for matrices and linear algebra.
#include <glm/glm.hpp>

namespace prt {
using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec2d = glm::dvec2;
using Vec3d = glm::dvec3;
using Mat3d = glm::dmat3;
/// Linear RGB radiance (or any per-channel quantity), float.
using Rgb = glm::vec3;

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2.0 * kPi;
inline constexpr double kFourPi = 4.0 * kPi;
}  // namespace prt
