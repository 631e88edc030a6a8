// Local frames: orthonormal, right-handed (t x b = n), stable near the poles, and the
// tangent-following variant.
#include "prtlab/sphere/local_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "support/random_directions.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 4242;

using testing::random_direction;

// Largest deviation from an orthonormal right-handed frame with the given normal.
double frame_error(const LocalFrame& f, const Vec3d& unit_normal) {
  double e = 0.0;
  e = std::max(e, std::abs(glm::length(f.t) - 1.0));
  e = std::max(e, std::abs(glm::length(f.b) - 1.0));
  e = std::max(e, std::abs(glm::length(f.n) - 1.0));
  e = std::max(e, std::abs(glm::dot(f.t, f.b)));
  e = std::max(e, std::abs(glm::dot(f.t, f.n)));
  e = std::max(e, std::abs(glm::dot(f.b, f.n)));
  e = std::max(e, glm::length(glm::cross(f.t, f.b) - f.n));
  e = std::max(e, glm::length(f.n - unit_normal));
  return e;
}

std::vector<Vec3d> test_normals() {
  std::vector<Vec3d> ns = {{0, 0, 1},     {0, 0, -1},      {1, 0, 0},        {-1, 0, 0},
                           {0, 1, 0},     {0, -1, 0},      {0, 0, -0.0},     {1e-9, 0, -1},
                           {0, 1e-9, -1}, {1e-17, 0, -1},  {-1e-9, 1e-9, 1}, {1, 1, 1},
                           {-1, -1, -1},  {1, 0, -1e-300}, {0.6, 0.8, 0.0}};
  ns[6] = {1e-12, 0, -0.0};  // z = -0: the sign bit alone picks the branch
  std::mt19937_64 rng(kSeed);
  for (int i = 0; i < 20000; ++i) ns.push_back(random_direction(rng));
  return ns;
}

TEST(LocalFrame, FromNormalIsOrthonormalAndRightHanded) {
  double worst = 0.0;
  for (const Vec3d& n : test_normals()) {
    const Vec3d unit = glm::normalize(n);
    const LocalFrame f = LocalFrame::from_normal(n);
    const double e = frame_error(f, unit);
    worst = std::max(worst, e);
    ASSERT_LT(e, 1e-14) << "normal (" << n.x << ", " << n.y << ", " << n.z << "), seed " << kSeed;
  }
  // Input scale does not matter.
  const LocalFrame a = LocalFrame::from_normal({0.3, -0.4, 0.5});
  const LocalFrame b = LocalFrame::from_normal({3.0, -4.0, 5.0});
  EXPECT_LT(glm::length(a.t - b.t) + glm::length(a.b - b.b) + glm::length(a.n - b.n), 1e-15);
}

TEST(LocalFrame, FromNormalAtThePolesIsTheIdentityUpToOrientation) {
  const LocalFrame up = LocalFrame::from_normal({0, 0, 1});
  EXPECT_EQ(up.t, Vec3d(1, 0, 0));
  EXPECT_EQ(up.b, Vec3d(0, 1, 0));
  const LocalFrame down = LocalFrame::from_normal({0, 0, -1});
  EXPECT_EQ(down.t, Vec3d(1, 0, 0));
  EXPECT_EQ(down.b, Vec3d(0, -1, 0));
}

TEST(LocalFrame, FromNormalIsContinuousAwayFromTheEquator) {
  // Small changes of n give small changes of the frame, including right next to -z, where the
  // classic Frisvad construction breaks down. (The only discontinuity is across z = 0.)
  std::mt19937_64 rng(kSeed + 1);
  const double eps = 1e-7;
  for (int i = 0; i < 5000; ++i) {
    Vec3d n = random_direction(rng);
    if (std::abs(n.z) < 0.05) continue;
    if (i % 2) n = glm::normalize(Vec3d{n.x * 1e-6, n.y * 1e-6, n.z});  // hug a pole
    const Vec3d m = glm::normalize(n + eps * random_direction(rng));
    if (m.z * n.z <= 0) continue;
    const LocalFrame a = LocalFrame::from_normal(n), b = LocalFrame::from_normal(m);
    const double dn = glm::length(n - m);
    ASSERT_LT(glm::length(a.t - b.t), 50 * dn) << "seed " << kSeed + 1;
    ASSERT_LT(glm::length(a.b - b.b), 50 * dn) << "seed " << kSeed + 1;
  }
}

TEST(LocalFrame, ToLocalAndToWorldRoundTrip) {
  std::mt19937_64 rng(kSeed + 2);
  for (int i = 0; i < 5000; ++i) {
    const LocalFrame f = LocalFrame::from_normal(random_direction(rng));
    const Vec3d d = 3.0 * random_direction(rng);
    EXPECT_LT(glm::length(f.to_world(f.to_local(d)) - d), 1e-14);
    EXPECT_LT(glm::length(f.to_local(f.to_world(d)) - d), 1e-14);
    EXPECT_LT(glm::length(f.to_local(f.n) - Vec3d(0, 0, 1)), 1e-15);
    EXPECT_LT(glm::length(f.to_local(f.t) - Vec3d(1, 0, 0)), 1e-15);
    EXPECT_LT(glm::length(f.to_local(f.b) - Vec3d(0, 1, 0)), 1e-15);
    EXPECT_NEAR(glm::length(f.to_local(d)), glm::length(d), 1e-14);
  }
}

TEST(LocalFrame, FromNormalTangentFollowsTheTangent) {
  std::mt19937_64 rng(kSeed + 3);
  for (int i = 0; i < 5000; ++i) {
    const Vec3d n = random_direction(rng);
    const Vec3d tangent = 2.0 * random_direction(rng);
    const Vec3d projected = tangent - n * glm::dot(n, tangent);
    if (glm::length(projected) < 1e-3) continue;
    const LocalFrame f = LocalFrame::from_normal_tangent(n, tangent);
    ASSERT_LT(frame_error(f, n), 1e-14) << "seed " << kSeed + 3;
    ASSERT_NEAR(glm::dot(f.t, glm::normalize(projected)), 1.0, 1e-14);
  }
  // Nearly parallel to n: still orthogonal to n to rounding (two Gram-Schmidt passes).
  const Vec3d n = glm::normalize(Vec3d{0.2, 0.3, 0.9});
  const LocalFrame f = LocalFrame::from_normal_tangent(n, n + Vec3d{1e-7, -2e-7, 0});
  EXPECT_LT(frame_error(f, n), 1e-14);
}

TEST(LocalFrame, FromNormalTangentFallsBackWhenTheTangentIsDegenerate) {
  const Vec3d n = glm::normalize(Vec3d{-0.5, 0.1, 0.7});
  const LocalFrame ref = LocalFrame::from_normal(n);
  for (const Vec3d& tangent : {Vec3d{0, 0, 0}, n, -3.0 * n, Vec3d{NAN, 0, 0}}) {
    const LocalFrame f = LocalFrame::from_normal_tangent(n, tangent);
    EXPECT_EQ(f.t, ref.t);
    EXPECT_EQ(f.b, ref.b);
    EXPECT_EQ(f.n, ref.n);
  }
}

// The unit-normal entry point is the general one without the normalisation: for a unit n the
// same frame bit for bit, including the fallback (here, n normalised exactly as
// from_normal_tangent normalises it).
TEST(LocalFrame, FromUnitNormalTangentEqualsFromNormalTangentForAUnitNormal) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 200; ++i) {
    const Vec3d raw = 3.0 * prt::testing::random_direction(rng);
    const Vec3d n = raw / glm::length(raw);
    for (const Vec3d& tangent : {prt::testing::random_direction(rng), Vec3d{0, 0, 0}, 2.0 * n}) {
      const LocalFrame a = LocalFrame::from_normal_tangent(raw, tangent);
      const LocalFrame b = LocalFrame::from_unit_normal_tangent(n, tangent);
      EXPECT_EQ(a.t, b.t);
      EXPECT_EQ(a.b, b.b);
      EXPECT_EQ(a.n, b.n);
      EXPECT_NEAR(glm::dot(b.t, b.n), 0.0, 1e-12);
    }
  }
}

}  // namespace
}  // namespace prt
