#include "isochor/core/input_file.hpp"
#include "isochor/core/bvh.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {

// Whitespace-separated tokens with their line numbers.
class Tokens {
 public:
  Tokens(const std::string& text, std::string name) : name_(std::move(name)) {
    std::istringstream in(text);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      std::istringstream ls(line);
      std::string w;
      while (ls >> w) words_.push_back({w, n});
    }
  }
  bool done() const { return pos_ >= words_.size(); }
  const std::string& peek() const {
    static const std::string end = "<end of file>";
    return done() ? end : words_[pos_].text;
  }
  std::size_t remaining() const { return words_.size() - pos_; }
  std::string next(const std::string& expected) {
    if (done()) fail("expected " + expected + ", found the end of the file");
    return words_[pos_++].text;
  }
  void expect(const std::string& word) {
    const std::string w = next("\"" + word + "\"");
    if (w != word) fail_at_previous("expected \"" + word + "\", found \"" + w + "\"");
  }
  double number(const std::string& what) {
    const std::string w = next(what);
    try {
      std::size_t used = 0;
      const double v = std::stod(w, &used);
      if (used == w.size() && std::isfinite(v)) return v;
    } catch (...) {
    }
    fail_at_previous("expected " + what + " (a finite number), found \"" + w + "\"");
  }
  [[noreturn]] void fail(const std::string& msg) const { fail_at(pos_, msg); }
  // At the token just read.
  [[noreturn]] void fail_at_previous(const std::string& msg) const { fail_at(pos_ == 0 ? 0 : pos_ - 1, msg); }
  [[noreturn]] void fail_at(std::size_t at, const std::string& msg) const {
    const int line = words_.empty() ? 1 : words_[std::min(at, words_.size() - 1)].line;
    throw Error(name_ + ":" + std::to_string(line) + ": " + msg);
  }

 private:
  struct Word {
    std::string text;
    int line;
  };
  std::string name_;
  std::vector<Word> words_;
  std::size_t pos_ = 0;
};

BvhJoint::Channel channel(Tokens& tk) {
  const std::string w = tk.next("a channel name");
  for (int c = 0; c < 6; ++c)
    if (w == bvh_channel_name(static_cast<BvhJoint::Channel>(c))) return static_cast<BvhJoint::Channel>(c);
  tk.fail_at_previous("expected a channel (Xposition ... Zrotation), found \"" + w + "\"");
}

Eigen::Vector3d offset(Tokens& tk) {
  tk.expect("OFFSET");
  Eigen::Vector3d o;
  for (int k = 0; k < 3; ++k) o[k] = tk.number("an OFFSET coordinate");
  return o;
}

// Joints nested deeper than this are refused (a body's skeleton is some tens deep): the parser
// recurses once per level.
constexpr int kMaxJointDepth = 256;

// A JOINT or ROOT body (after its name): offset, channels, children, End Site.
void joint_body(Tokens& tk, Bvh& b, int self, int& columns, int depth) {
  if (depth > kMaxJointDepth)
    tk.fail_at_previous("joints nested more than " + std::to_string(kMaxJointDepth) + " deep (expected a skeleton)");
  tk.expect("{");
  b.joints[self].offset = offset(tk);
  tk.expect("CHANNELS");
  const double n = tk.number("the number of channels");
  if (n < 0 || n > 6 || n != static_cast<int>(n)) tk.fail_at_previous("expected 0 to 6 channels");
  b.joints[self].first_channel = columns;
  for (int c = 0; c < static_cast<int>(n); ++c) b.joints[self].channels.push_back(channel(tk));
  columns += static_cast<int>(n);
  while (tk.peek() != "}") {
    const std::string w = tk.next("JOINT, End Site or }");
    if (w == "JOINT") {
      BvhJoint j;
      j.name = tk.next("a joint name");
      if (b.find(j.name) >= 0) tk.fail_at_previous("joint \"" + j.name + "\" is defined twice");
      j.parent = self;
      b.joints.push_back(j);
      joint_body(tk, b, static_cast<int>(b.joints.size()) - 1, columns, depth + 1);
    } else if (w == "End") {
      tk.expect("Site");
      tk.expect("{");
      offset(tk);
      tk.expect("}");
    } else {
      tk.fail_at_previous("expected JOINT, End Site or }, found \"" + w + "\"");
    }
  }
  tk.expect("}");
}

}  // namespace

const char* bvh_channel_name(BvhJoint::Channel c) {
  static const char* names[] = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"};
  return names[c];
}

int Bvh::find(const std::string& name) const {
  for (std::size_t j = 0; j < joints.size(); ++j)
    if (joints[j].name == name) return static_cast<int>(j);
  return -1;
}

Bvh parse_bvh(const std::string& text, const std::string& name) {
  Tokens tk(text, name);
  Bvh b;
  tk.expect("HIERARCHY");
  tk.expect("ROOT");
  BvhJoint root;
  root.name = tk.next("the root joint's name");
  b.joints.push_back(root);
  int columns = 0;
  joint_body(tk, b, 0, columns, 1);
  tk.expect("MOTION");
  tk.expect("Frames:");
  const double frames = tk.number("the number of frames");
  if (frames < 1 || frames != static_cast<long>(frames))
    tk.fail_at_previous("expected a positive whole number of frames");
  tk.expect("Frame");
  tk.expect("Time:");
  b.frame_time = tk.number("the frame time (s)");
  if (!(b.frame_time > 0)) tk.fail_at_previous("expected a positive frame time (s)");
  // A large count of values the file cannot hold is refused before anything is allocated for
  // it (a short small file says below which frame ends early).
  if (frames * columns > 1e6 && frames * columns > static_cast<double>(tk.remaining()))
    tk.fail("Frames: " + std::to_string(static_cast<long long>(frames)) + " frames of " + std::to_string(columns) +
            " channels need " + std::to_string(static_cast<long long>(frames) * columns) + " values, the file holds " +
            std::to_string(tk.remaining()));
  b.motion.resize(static_cast<Eigen::Index>(frames), columns);
  for (Eigen::Index f = 0; f < b.motion.rows(); ++f)
    for (int c = 0; c < columns; ++c) {
      if (tk.done())
        tk.fail("frame " + std::to_string(f) + " has " + std::to_string(c) + " values, expected " +
                std::to_string(columns) + " (one per channel)");
      b.motion(f, c) = tk.number("a channel value");
    }
  if (!tk.done())
    tk.fail("more values than " + std::to_string(b.motion.rows()) + " frames x " + std::to_string(columns) +
            " channels");
  return b;
}

Bvh read_bvh(const std::string& path) {
  return parse_bvh(read_input_file(path, "a BVH motion file", input_limits::kMotion), path);
}

}  // namespace isochor
