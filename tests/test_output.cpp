#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/core/output.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/core/progress.hpp"

#include <chrono>
#include <thread>
#include "test_util.hpp"

using namespace isochor;
namespace fs = std::filesystem;

namespace {

// Frame k: every node moved by (k, 2k, 3k) * 0.01 and the whole mesh scaled in z by 1 + 0.1 k.
Points frame_positions(const Mesh& m, int k) {
  Points x = m.rest_positions();
  x.row(2) *= 1.0 + 0.1 * k;
  for (int i = 0; i < x.cols(); ++i) x.col(i) += 0.01 * k * Eigen::Vector3d(1, 2, 3);
  return x;
}

void write_frames(OutputWriter& w, const Mesh& m, int first, int count, bool zones = true) {
  for (int k = first; k < first + count; ++k) {
    Points x = frame_positions(m, k);
    Frame f;
    f.time = 0.5 * k;
    f.positions = &x;
    f.volumes = {tets_volume(x, m.tets())};
    if (zones) f.volumes.push_back(0.5 * tets_volume(x, m.tets()));
    f.energy = {1.0 * k, 2.0 * k, 3.0 * k};
    std::vector<double> p(m.num_tets(), 10.0 * k);
    f.pressure = &p;
    f.stats = {{"steps", 4.0 * k}};
    Points load = Points::Zero(3, m.num_nodes());  // node i: (0.001 i, 0, k) N
    for (int i = 0; i < m.num_nodes(); ++i) load.col(i) << 0.001 * i, 0.0, k;
    f.loads = &load;
    w.write_frame(f);
  }
}

Mesh test_mesh() {
  Mesh m = make_box(Eigen::Vector3d(1, 2, 3), {2, 3, 4}, Eigen::Vector3d::Zero(), 6);
  return m;
}

std::vector<std::pair<std::string, std::vector<int>>> half_zone(const Mesh& m) {
  std::vector<int> half;
  for (int e = 0; e < m.num_tets() / 2; ++e) half.push_back(e);
  return {{"half", half}};
}

}  // namespace

TEST(Output, RoundTripThroughTheReader) {
  fs::path d = test::temp_dir();
  Mesh m = test_mesh();
  const std::string path = (d / "run.h5").string();
  {
    OutputWriter w(path, m, half_zone(m), {"[mesh]\nshape = \"box\"\n", "scene.toml", "test", {}, {}}, true);
    write_frames(w, m, 0, 4);
    w.set_stat("wall_seconds", 1.25);
  }
  RunFile r(path);
  EXPECT_EQ(r.num_nodes(), m.num_nodes());
  EXPECT_EQ(r.num_tets(), m.num_tets());
  EXPECT_EQ(r.num_frames(), 4);
  EXPECT_EQ(r.times(), (std::vector<double>{0, 0.5, 1.0, 1.5}));
  EXPECT_EQ(r.zone_names(), std::vector<std::string>{"half"});
  EXPECT_EQ((r.positions(3) - frame_positions(m, 3)).cwiseAbs().maxCoeff(), 0.0);
  // Volume scales with the z stretch: V_k = V_0 (1 + 0.1 k).
  EXPECT_NEAR(r.volumes()[2][0], 6.0 * 1.2, 1e-12);
  EXPECT_EQ(r.attributes()["scene"], "[mesh]\nshape = \"box\"\n");
  EXPECT_EQ(r.attributes()["isochor_version"], isochor_version());
  EXPECT_EQ(r.stat_totals()["wall_seconds"], 1.25);
  EXPECT_EQ(r.stat_series()["steps"], (std::vector<double>{0, 4, 8, 12}));
  const std::string info = describe_run(path);
  EXPECT_NE(info.find("frames      4, t = 0 .. 1.5 s"), std::string::npos) << info;
  EXPECT_NE(info.find("drift 3.000e-01"), std::string::npos) << info;  // 1.3 / 1.0 - 1
}

// isochor info lists a run's zones by name, the first 12 of them and a count of the rest (per-node
// zones are thousands: one line of every name was 120 KB at 6,752).
TEST(Output, InfoListsTheFirstZonesAndCountsTheRest) {
  fs::path d = test::temp_dir();
  Mesh m = test_mesh();
  std::vector<std::pair<std::string, std::vector<int>>> zones;
  for (int e = 0; e < 20; ++e) zones.push_back({"z" + std::to_string(100 + e), {e}});
  const std::string path = (d / "zones.h5").string();
  { OutputWriter w(path, m, zones, {"", "", "test", {}, {}}, true); }
  const std::string info = describe_run(path);
  EXPECT_NE(info.find("zones       20: z100 (1 tets), "), std::string::npos) << info;
  EXPECT_NE(info.find("z111 (1 tets), and 8 more\n"), std::string::npos) << info;
  EXPECT_EQ(info.find("z112"), std::string::npos) << info;
}

TEST(Output, MeshioReadsTheXdmfTimeSeries) {
  fs::path d = test::temp_dir();
  Mesh m = test_mesh();
  const std::string path = (d / "series.h5").string();
  {
    OutputWriter w(path, m, half_zone(m), {"", "", "test", {}, {}}, true);
    write_frames(w, m, 0, 3);
  }
  // The Python side recomputes the expected positions from the formula above.
  const std::string cmd = std::string(ISOCHOR_PYTHON) + " " + ISOCHOR_SOURCE_DIR + "/tests/read_xdmf.py " +
                          (d / "series.xdmf").string() + " " + std::to_string(m.num_nodes()) + " " +
                          std::to_string(m.num_tets()) + " 3";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

TEST(Output, AKilledWriterKeepsEveryFinishedFrame) {
  fs::path d = test::temp_dir();
  Mesh m = test_mesh();
  const std::string path = (d / "killed.h5").string();
  pid_t pid = fork();
  if (pid == 0) {
    OutputWriter* w = new OutputWriter(path, m, half_zone(m), {"", "", "test", {}, {}}, false);
    write_frames(*w, m, 0, 3);
    _exit(0);  // no close, no destructors: as if killed
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  RunFile r(path);
  EXPECT_EQ(r.num_frames(), 3);
  EXPECT_EQ((r.positions(2) - frame_positions(m, 2)).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Output, ObjSequenceHasTheSurfaceOfEveryFrame) {
  fs::path d = test::temp_dir();
  Mesh m = test_mesh();
  const std::string path = (d / "seq.h5").string();
  {
    OutputWriter w(path, m, {}, {"", "", "test", {}, {}}, false);
    write_frames(w, m, 0, 2, false);
  }
  ASSERT_EQ(export_obj_sequence(path, (d / "obj").string(), "f"), 2);
  Points x;
  std::vector<Tri> tris;
  read_obj_surface((d / "obj" / "f_0001.obj").string(), x, tris);
  EXPECT_EQ(tris.size(), m.surface().size());
  // The surface encloses the frame's volume: 6 * 1.1.
  EXPECT_NEAR(surface_volume(x, tris), 6.0 * 1.1, 1e-6);
}

TEST(Output, UnwritablePathIsAnError) {
  Mesh m = test_mesh();
  std::string msg = test::error_of([&] {
    OutputWriter w("/proc/no/such/dir/x.h5", m, {}, {"", "", "", {}, {}}, false);
  });
  EXPECT_NE(msg.find("/proc/no/such/dir/x.h5"), std::string::npos) << msg;
}

TEST(Progress, PlainLinesWhenNotATerminal) {
  std::FILE* f = std::tmpfile();
  {
    Progress p("run", 10, 0.0, 1.0, f);
    p.update(1, 0.1);  // within the first second: nothing
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    p.update(4, 0.4);
  }
  std::rewind(f);
  char buf[256] = {0};
  std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  const std::string out(buf, n);
  EXPECT_EQ(out.find("frame 1 of"), std::string::npos) << out;
  EXPECT_NE(out.find("run: frame 4 of 10, t = 0.4 s, wall 1."), std::string::npos) << out;
  EXPECT_EQ(out.back(), '\n');
}

// The estimate follows the recent rate: a run that covered 90% of its simulated time in its first
// 10 s and 5% in the next 100 s has about 100 s left, not the 6 s the average since the start
// (110 s for 95%) would promise.
TEST(Progress, TheEstimateFollowsTheRecentRate) {
  std::deque<std::pair<double, double>> s{{0.0, 0.0}};
  for (int k = 1; k <= 10; ++k) s.emplace_back(k, 0.09 * k);
  for (int k = 1; k <= 100; ++k) s.emplace_back(10.0 + k, 0.9 + 0.0005 * k);
  EXPECT_NEAR(remaining_seconds(s, 1.0), 100.0, 1e-9);  // 0.05 left at 0.0005 per second
  // A steady run: the average and the recent rate agree.
  std::deque<std::pair<double, double>> steady{{0.0, 0.0}, {30.0, 0.3}, {60.0, 0.6}};
  EXPECT_NEAR(remaining_seconds(steady, 1.0), 40.0, 1e-9);
  EXPECT_LT(remaining_seconds({{0.0, 0.0}}, 1.0), 0.0);  // no rate yet
  // Steps that have all but stopped (2 us of 2 s in 4 min): a bound, not an int's overflow.
  EXPECT_EQ(duration_text(remaining_seconds({{0.0, 0.0}, {240.0, 2e-6}}, 2.0)), "over 1000h");
  EXPECT_EQ(duration_text(12.34), "12.3s");
  EXPECT_EQ(duration_text(245.0), "4m05s");
  EXPECT_EQ(duration_text(3.6e6 - 60), "999h59m");
}

// Between frames, a log gets a line at least every 30 s with the time the steps have reached.
TEST(Progress, ALineEvenWhenNoFrameFinishes) {
  std::FILE* f = std::tmpfile();
  {
    Progress p("slow", 10, 0.0, 1.0, f, [] { return 0.25; });
    p.set_heartbeat(1.5);  // (30 s in a run)
    p.update(0, 0.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(2200));
  }
  std::rewind(f);
  char buf[256] = {0};
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  const std::string out(buf, n);
  EXPECT_NE(out.find("slow: steps past frame 0 of 10, t = 0.25 s, wall "), std::string::npos) << out;
  EXPECT_EQ(out.find('\n'), out.size() - 1) << out;  // one line, not one per wake-up
}
