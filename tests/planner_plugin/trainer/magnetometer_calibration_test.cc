#include "planner_plugin/trainer/magnetometer_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "shape/core/error.h"
#include "tests/planner_plugin/trainer/synthetic_imu.h"

namespace pectus::trainer {
namespace {

TEST(MagnetometerCalibration, RecoversTheKnownHardAndSoftIronFromACalibrationWave) {
  for (unsigned seed : {1u, 2u, 3u}) {
    testing::SyntheticImuOptions o;
    o.seed = seed;
    o.duration_s = 1;  // the calibration wave only
    const testing::SyntheticImu imu = testing::MakeSyntheticImu(o);
    const MagnetometerCalibration c = FitMagnetometerCalibration(imu.calibration_mag_uT);
    // The offset (up to 40 uT per axis) within 0.3 uT; the correction undoes the soft iron up to a scale
    // (W S = s I); the corrected readings on a sphere to within their noise (0.6 uT per axis).
    const double offset_error = (c.hard_iron_offset - imu.hard_iron_uT).norm();
    const Eigen::Matrix3d WS = c.soft_iron_correction * imu.soft_iron;
    const double soft_error = (WS / std::cbrt(WS.determinant()) - Eigen::Matrix3d::Identity()).norm();
    std::printf(
        "seed %u: hard iron |%.1f| uT found within %.3f uT, soft iron within %.4f (|W S / s - I|), residual "
        "%.3f uT\n",
        seed, imu.hard_iron_uT.norm(), offset_error, soft_error, c.rms_residual);
    EXPECT_LT(offset_error, 0.3);
    EXPECT_LT(soft_error, 0.01);
    EXPECT_LT(c.rms_residual, 0.7);
    EXPECT_NEAR(c.field_strength, 50, 5);
  }
  // Readings in one plane (the scope turned about one axis only) do not determine the ellipsoid.
  std::vector<Eigen::Vector3d> flat;
  for (int i = 0; i < 50; ++i) flat.push_back({50 * std::cos(0.2 * i), 50 * std::sin(0.2 * i), 7});
  EXPECT_THROW(FitMagnetometerCalibration(flat, "flat.txt"), Error);
  EXPECT_THROW(FitMagnetometerCalibration({{1, 2, 3}}), Error);
}

}  // namespace
}  // namespace pectus::trainer
