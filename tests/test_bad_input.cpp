// Bad input by class: files that are not regular files or are too large for their format,
// non-finite numbers in every reader, nesting and counts a file cannot hold, lengths no body
// has, steps longer than the run, and a refused resume that leaves its file as it was. Each
// asserts the one-line message (naming the file or key and what was expected) and what is left.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <hdf5.h>

#include "isochor/app/run.hpp"
#include "isochor/core/bvh.hpp"
#include "isochor/core/input_file.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/core/paint.hpp"
#include "isochor/scene/scene.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string kBox = "[mesh]\nshape = \"box\"\ncells = 2\n";

std::string scene_error(const std::string& text) {
  return test::error_of([&] { parse_scene(SceneFile::parse(text, "bad.toml")); });
}

}  // namespace

TEST(BadInput, FilesThatAreNotRegularFilesAreRefusedBeforeReading) {
  const auto dir = test::temp_dir();
  const std::string fifo = (dir / "pipe.toml").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // A FIFO would block the reader (no writer), /dev/zero would fill memory: both refused by kind.
  EXPECT_TRUE(has(test::error_of([&] { load_scene(fifo); }),
                  "pipe.toml: is a FIFO (named pipe), not a regular file (expected a scene file in TOML)"));
  EXPECT_TRUE(has(test::error_of([&] { load_scene("/dev/zero"); }),
                  "/dev/zero: is a character device, not a regular file (expected a scene file in TOML)"));
  EXPECT_TRUE(has(test::error_of([&] { read_bvh("/dev/urandom"); }), "/dev/urandom: is a character device"));
  EXPECT_TRUE(has(test::error_of([&] { read_paint("/dev/zero.csv", nullptr); }), "no such file"));
  EXPECT_TRUE(
      has(test::error_of([&] { RunFile f(dir.string()); }), ": is a directory (expected an isochor .h5 output)"));
  const std::string mesh_fifo = (dir / "body.stl").string();
  ASSERT_EQ(::mkfifo(mesh_fifo.c_str(), 0600), 0);
  EXPECT_TRUE(has(scene_error("[mesh]\nfile = \"" + mesh_fifo + "\"\n"), "body.stl: is a FIFO (named pipe)"));
}

TEST(BadInput, AFileLargerThanItsFormatAllowsIsRefusedBeforeReading) {
  const auto dir = test::temp_dir();
  const std::string big = test::write_file(dir / "big.toml", std::string(3000, '#') + "\n");
  EXPECT_TRUE(has(test::error_of([&] { check_input_file(big, "a scene file in TOML", 2000); }),
                  "big.toml: 0.003 MB, more than the 0.002 MB that a scene file in TOML may have here"));
  EXPECT_NO_THROW(check_input_file(big, "a scene file in TOML", 3001));
}

TEST(BadInput, NonFiniteNumbersAreRefusedInPaintAndMotion) {
  const auto dir = test::temp_dir();
  // A NaN weight is in no zone and not out of one either: refused, naming the vertex and column.
  const std::string csv = test::write_file(dir / "w.csv", "x,y,z,weight\n0,0,0,1\n1,0,0,nan\n");
  EXPECT_TRUE(has(test::error_of([&] { read_paint(csv, nullptr); }), "w.csv: vertex 1's weight is NaN"));
  const std::string inf = test::write_file(dir / "i.csv", "x,y,z,weight\n0,0,0,inf\n");
  EXPECT_TRUE(has(test::error_of([&] { read_paint(inf, nullptr); }), "i.csv: vertex 0's weight is infinite"));
  const std::string head = "HIERARCHY\nROOT hips\n{\n OFFSET 0 0 0\n CHANNELS 1 Zrotation\n}\nMOTION\nFrames: 2\n";
  EXPECT_TRUE(has(test::error_of([&] { parse_bvh(head + "Frame Time: inf\n0\n1\n", "t.bvh"); }),
                  "t.bvh:9: expected the frame time (s) (a finite number), found \"inf\""));
  EXPECT_TRUE(has(test::error_of([&] { parse_bvh(head + "Frame Time: 0.1\n0\nnan\n", "n.bvh"); }),
                  "n.bvh:11: expected a channel value (a finite number), found \"nan\""));
}

TEST(BadInput, MotionFilesCannotNestOrCountBeyondWhatTheyHold) {
  // 300 joints each inside the last: refused at the 257th level, without deep recursion.
  std::string deep = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 0\n";
  for (int k = 1; k < 300; ++k) deep += "JOINT j" + std::to_string(k) + "\n{\nOFFSET 0 0 1\nCHANNELS 0\n";
  EXPECT_TRUE(has(test::error_of([&] { parse_bvh(deep, "deep.bvh"); }), "joints nested more than 256 deep"));
  // A frame count that the file cannot hold is refused before any memory is taken for it.
  const std::string huge =
      "HIERARCHY\nROOT hips\n{\n OFFSET 0 0 0\n CHANNELS 1 Zrotation\n}\nMOTION\nFrames: 99999999999\nFrame Time: "
      "0.1\n0\n";
  EXPECT_TRUE(has(test::error_of([&] { parse_bvh(huge, "huge.bvh"); }),
                  "Frames: 99999999999 frames of 1 channels need 99999999999 values, the file holds 1"));
}

TEST(BadInput, LengthsAndStepsAreCheckedAgainstWhatTheyCanMean) {
  EXPECT_TRUE(has(scene_error(kBox + "[[collider]]\nshape = \"sphere\"\nradius = 1e200\ncenter = [0.0, 0.0, -5.0]\n"),
                  "collider[0].radius: expected a number in (0, 1e+06]"));
  EXPECT_TRUE(has(scene_error(kBox + "[[collider]]\nshape = \"sphere\"\nradius = 1.0\ncenter = [0.0, 0.0, -1e300]\n"),
                  "collider[0].center: expected a list of numbers, each a number in [-1e+06, 1e+06], got -1e+300"));
  const std::string obj = std::string(ISOCHOR_SOURCE_DIR) + "/demos/meshes/jelly_yup.obj";
  EXPECT_TRUE(has(scene_error(kBox + "[[collider]]\nshape = \"mesh\"\nfile = \"" + obj +
                              "\"\ncenter = [0.0, 0.0, -5.0]\nscale = 1e20\n"),
                  "collider[0].scale: 1e+20 makes the surface 1.06e+19 m across (expected 1e-06 to 1e+06 m"));
  // A fixed step longer than the run would take no step at all: refused, not skipped.
  for (const char* kind : {"backward_euler", "semi_implicit", "xpbd"})
    EXPECT_TRUE(has(scene_error(kBox + "[integrator]\nkind = \"" + std::string(kind) +
                                "\"\ndt = 1e20\n[frames]\nrate = 100.0\nduration = 0.02\n"),
                    "integrator.dt: 1e+20 s is longer than the run (frames.duration = 0.02 s)"))
        << kind;
  EXPECT_TRUE(has(scene_error("[mesh]\nshape = \"box\"\nsize = [1e-300, 1.0, 1.0]\n"),
                  "mesh.size: 1e-300 m is too small to mesh"));
  // Zones flattened to volume 0 cannot be held at their rest volumes from t = 0 on IDA.
  EXPECT_TRUE(has(scene_error(kBox + "[material]\nmodel = \"cnh\"\n[initial]\nflatten = \"z\"\n"),
                  "initial.flatten: starts every zone at volume 0, which IDA cannot hold to its rest volume at t = 0 "
                  "(expected zones.restore_time > 0"));
  // A mesh file of 1e-300 m (its masses underflow to 0: "mass() must hold 12 positive entries",
  // naming nothing) or of 1e300 m: refused by the mesh, naming its file.
  for (double size : {1e-300, 1e-7, 1e7, 1e300}) {
    char across[32];
    std::snprintf(across, sizeof across, "%.3g", size);
    Points x = Points::Zero(3, 4);
    x(0, 1) = x(1, 2) = x(2, 3) = size;
    EXPECT_TRUE(has(test::error_of([&] {
                      Mesh(x, {Tet{0, 1, 2, 3}}, "tiny.ele");
                    }),
                    "tiny.ele: the mesh is " + std::string(across) + " m across"))
        << size;
  }
  for (double size : {1e-6, 1e6}) {
    Points x = Points::Zero(3, 4);
    x(0, 1) = x(1, 2) = x(2, 3) = size;
    EXPECT_NEAR(Mesh(x, {Tet{0, 1, 2, 3}}, "tiny.ele").rest_volume(), size * size * size / 6,
                1e-12 * size * size * size);
  }
  // A surface file meshed at an edge length it cannot fit gets the shapes' estimate before Gmsh runs.
  EXPECT_TRUE(
      has(scene_error("[mesh]\nfile = \"" + obj + "\"\nedge_length = 1e-5\n"), "mesh.edge_length: makes about"));
}

// A scene string is a path, a name or a choice: one longer than a path may be is refused naming
// the key (a 60 MB output.path was taken to the file system, and its error quoted all of it), and
// no message quotes megabytes of what it was given.
TEST(BadInput, ScenesStringsAndMessagesHaveALength) {
  const std::string at_limit(4096, 'a'), over(4097, 'a'), huge(8u << 20, 'b');
  EXPECT_EQ(scene_error(kBox + "[output]\npath = \"" + at_limit + "\"\n").find("at most 4096 bytes"),
            std::string::npos);
  const std::string long_path = scene_error(kBox + "[output]\npath = \"" + over + "\"\n");
  EXPECT_TRUE(has(long_path, "bad.toml:5: output.path: expected a string of at most 4096 bytes"));
  EXPECT_TRUE(has(long_path, "got 4097 bytes"));
  EXPECT_TRUE(has(scene_error(kBox + "[zones]\nglobal = false\n[[zones.paint]]\ngroups = [\"" + over + "\"]\n"),
                  "zones.paint[0].groups: expected a string of at most 4096 bytes"));
  // An unknown key of 8 MB: the message keeps its start (file and line) and its end (what was
  // expected), and says how much of the middle it left out.
  const std::string message = scene_error(kBox + huge + " = 1\n");
  EXPECT_LE(message.size(), kMaxMessageBytes + 64);
  EXPECT_TRUE(has(message, "bad.toml:4")) << message.substr(0, 200);
  EXPECT_TRUE(has(message, "bytes left out ...]"));
  EXPECT_EQ(message.find('\n'), std::string::npos);
  // Cut between UTF-8 characters, never inside one: a message of 3-byte characters stays valid.
  std::string wide;
  for (int i = 0; i < 2000; ++i) wide += "\u2212";
  const std::string cut = Error(wide).what();
  const auto tail = cut.substr(cut.find("...] ") + 5);
  EXPECT_EQ(tail.size() % 3, 0u);
  EXPECT_EQ(cut.substr(0, cut.find(" [...")).size() % 3, 0u);
}

// A key of 50,000 dotted parts (a table header, a dotted key, a --set) overflowed the stack inside
// toml++; more than 256 parts on a line are refused before parsing, while dots in numbers,
// strings and comments are not counted.
TEST(BadInput, DottedKeysCannotNestBeyondWhatAScenesTablesHave) {
  auto parts = [](const std::string& part, int n) {
    std::string k = part;
    for (int i = 1; i < n; ++i) k += "." + part;
    return k;
  };
  const std::string refused = "keys of more than 256 dotted parts";
  EXPECT_TRUE(has(scene_error(kBox + "[" + parts("a", 50000) + "]\n"), "bad.toml:4: " + refused));
  EXPECT_TRUE(has(scene_error(kBox + parts("b", 50000) + " = 1\n"), "bad.toml:4: " + refused));
  EXPECT_TRUE(has(scene_error(kBox + "c = { " + parts("d", 300) + " = 1 }\n"), refused));
  EXPECT_TRUE(has(scene_error(kBox + parts("1", 300) + " = 1\n"), refused));
  EXPECT_TRUE(has(scene_error(kBox + parts(" \"c\" ", 300) + " = 1\n"), refused));
  EXPECT_TRUE(
      has(test::error_of([&] { SceneFile::parse(kBox, "bad.toml", {parts("e", 50000) + "=1"}); }), "--set e.e.e"));
  // 256 parts are parsed (and then named as the unknown key they are).
  EXPECT_TRUE(has(scene_error(kBox + "[" + parts("a", 256) + "]\n"), "bad.toml:4: a: unknown key"));
  // Numbers, strings, comments and multi-line strings with their dots are a scene's values.
  std::string floats = "[";
  for (int i = 0; i < 3000; ++i) floats += (i ? ", " : "") + std::to_string(i) + ".5e-3";
  floats += "]";
  const std::string dots(3000, '.');
  const std::string fine = kBox + "# " + dots + "\n[output]\npath = \"" + dots + "\"\nnote = '''\n" + dots + "\n" +
                           dots + "'''\n[frames]\ntimes = " + floats + "\n";
  const std::string error = scene_error(fine);
  EXPECT_EQ(error.find(refused), std::string::npos) << error.substr(0, 300);
  EXPECT_TRUE(has(error, "unknown key")) << error.substr(0, 300);  // parsed: `note` and `times` are not scene keys
}

// Stiffness, density, acceleration and speed no body has: refused naming the key (they overflowed
// or underflowed the forces and masses, and IDA stopped at t = 0 naming no key, or blamed nu).
TEST(BadInput, MaterialAndMotionNumbersAreCheckedAgainstWhatTheyCanMean) {
  const std::pair<std::string, std::string> refused[] = {
      {"[material]\nE = 1e308\nnu = 0.3\n", "material.E: expected a number in (0, 1e+13], got 1e+308"},
      {"[material]\nmu = 1e20\n", "material.mu: expected a number in (0, 1e+13]"},
      {"[material]\nlambda = 1e20\n", "material.lambda: expected a number in [0, 1e+13]"},
      {"[material]\ndensity = 1e-308\n", "material.density: expected a number in [0.001, 1e+06], got 1e-308"},
      {"[forces]\ngravity = [0.0, 0.0, -1e300]\n",
       "forces.gravity: expected a list of numbers, each a number in [-1e+07, 1e+07], got -1e+300"},
      {"[initial]\nvelocity = [0.0, 0.0, 1e200]\n",
       "initial.velocity: expected a list of numbers, each a number in [-100000, 100000], got 1e+200"},
      {"[damping]\nalpha = 1e300\n", "damping.alpha: expected a number in [0, 1e+06]"},
      {"[damping]\nbeta = 1e300\n", "damping.beta: expected a number in [0, 1000]"},
      // Tolerances that accept any step: a relative one above 1, an absolute one longer than a body.
      {"[integrator]\nkind = \"ida\"\nrtol = 2.0\n", "integrator.rtol: expected a number in (0, 1], got 2"},
      {"[integrator]\nkind = \"ida\"\natol = 1e300\n", "integrator.atol: expected a number in (0, 1e+06], got 1e+300"},
      // A frame interval longer than the run would write frame 0 alone.
      {"[frames]\nrate = 0.5\nduration = 1.0\n",
       "frames.rate: 0.5 frames per second put the frame after t = 0 at 2 s, past the run's end"}};
  for (const auto& [text, message] : refused) EXPECT_TRUE(has(scene_error(kBox + text), message)) << text;
  // The bounds leave every real scene alone: a stiff, dense, fast case still parses.
  EXPECT_EQ(scene_error(kBox + "[material]\nE = 1.2e12\nnu = 0.2\ndensity = 22590.0\n[initial]\nvelocity = "
                               "[0.0, 0.0, -3000.0]\n[forces]\ngravity = [0.0, 0.0, -1e5]\n"),
            "");
}

TEST(BadInput, ARefusedResumeLeavesItsFileAsItWas) {
  const auto dir = test::temp_dir();
  const std::string path = (dir / "run.h5").string(), xdmf = (dir / "run.xdmf").string();
  const Scene sc = parse_scene(SceneFile::parse(kBox + "[frames]\nrate = 100.0\nduration = 0.05\n", "r.toml"));
  RunOptions o;
  o.output = path;
  o.progress = false;
  o.on_frame = [](int k, const Frame&) { return k < 2; };
  EXPECT_THROW(run_scene(sc, o), RunInterrupted);
  // Frame 2's time moved off the scene's frames: the resume is refused after the file was opened.
  {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(f, "/frames/time", H5P_DEFAULT);
    double t[3];
    H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t);
    t[2] = 0.0123;
    H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t);
    H5Dclose(ds);
    H5Fclose(f);
  }
  const std::string h5_before = file_bytes(path), xdmf_before = file_bytes(xdmf);
  o.mode = OutputWriter::Mode::resume;
  o.on_frame = nullptr;
  EXPECT_TRUE(has(test::error_of([&] { run_scene(sc, o); }), "is not a frame of the scene (cannot be resumed)"));
  EXPECT_EQ(file_bytes(path), h5_before);
  EXPECT_EQ(file_bytes(xdmf), xdmf_before);
  RunFile f(path);
  EXPECT_EQ(f.attributes().at("status"), "interrupted");
  EXPECT_EQ(f.stat_totals().count("interrupted_at"), 1u);
  // A file that is not HDF5 at all is refused as such, and left as it was (here: empty).
  const std::string empty = test::write_file(dir / "empty.h5", "");
  o.output = empty;
  EXPECT_TRUE(has(test::error_of([&] { run_scene(sc, o); }), "empty.h5: not an HDF5 file"));
  EXPECT_EQ(std::filesystem::file_size(empty), 0u);
}

TEST(BadInput, OutputsGoWhereTheUserSaidAndNowhereElse) {
  const auto dir = test::temp_dir();
  // The sidecar's path is a directory: refused before the run's file is created.
  std::filesystem::create_directories(dir / "run.xdmf");
  const Scene sc = parse_scene(SceneFile::parse(kBox + "[frames]\nrate = 100.0\nduration = 0.02\n", "o.toml"));
  RunOptions o;
  o.output = (dir / "run.h5").string();
  o.progress = false;
  EXPECT_TRUE(has(test::error_of([&] { run_scene(sc, o); }), "run.xdmf: is a directory (the run's XDMF sidecar"));
  EXPECT_FALSE(std::filesystem::exists(dir / "run.h5"));
  // An OBJ prefix is a file name's start: one with a '/' would write outside --dir.
  o.output = (dir / "good.h5").string();
  run_scene(sc, o);
  const std::string out = (dir / "obj").string();
  EXPECT_TRUE(has(test::error_of([&] { export_obj_sequence(o.output, out, "../../x"); }),
                  "--prefix ../../x: expected the start of a file name (no '/')"));
  EXPECT_FALSE(std::filesystem::exists(dir / "obj"));
  EXPECT_EQ(export_obj_sequence(o.output, out, "f"), 3);
  EXPECT_TRUE(std::filesystem::exists(dir / "obj" / "f_0002.obj"));
  EXPECT_FALSE(std::filesystem::exists(dir / "obj" / "f_0002.obj.part"));
}
