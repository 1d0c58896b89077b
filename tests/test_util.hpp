// Helpers shared by the tests: temporary directories and files.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "isochor/base/error.hpp"
#include "isochor/core/mesh.hpp"

namespace isochor::test {

inline std::filesystem::path temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  // Per process: two test runs on one machine (a CI clone beside a work tree) must not share files.
  std::filesystem::path d = std::filesystem::temp_directory_path() / "isochor_tests" / std::to_string(::getpid()) /
                            (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// Frame times 0, dt, 2 dt, ... up to end.
inline std::vector<double> frame_times(double end, double dt) {
  std::vector<double> t;
  for (int k = 0; k * dt <= end + 1e-12; ++k) t.push_back(k * dt);
  return t;
}

inline std::string write_file(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

// Runs f and returns the message of the isochor::Error it throws ("" if none).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const isochor::Error& e) {
    return e.what();
  }
  return "";
}

// A mesh's surface is closed (each edge in two triangles), consistently and outward oriented
// (its divergence-theorem volume equals the sum of tet volumes), with Euler characteristic 2.
inline void expect_closed_outward(const isochor::Mesh& m) {
  const isochor::SurfaceCheck c = isochor::check_surface(m.surface());
  EXPECT_TRUE(c.closed);
  EXPECT_TRUE(c.oriented);
  EXPECT_EQ(c.euler_characteristic, 2);
  EXPECT_NEAR(isochor::surface_volume(m.rest_positions(), m.surface()) / m.rest_volume(), 1.0, 1e-12);
  double sum = 0;
  for (double v : m.rest_volumes()) {
    EXPECT_GT(v, 0.0);
    sum += v;
  }
  EXPECT_NEAR(sum / m.rest_volume(), 1.0, 1e-14);
}

}  // namespace isochor::test
