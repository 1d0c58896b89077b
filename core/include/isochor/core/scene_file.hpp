// Scene files in TOML. A Section reads typed keys with defaults and ranges; every failure is one
// line `file:line: key: what was expected`. Keys that nothing read are reported as unknown by
// SceneFile::check_unknown_keys() once the whole scene has been parsed.
#pragma once
#include <Eigen/Core>
#include <array>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace toml {
inline namespace v3 {
class node;
class table;
}  // namespace v3
}  // namespace toml

namespace isochor {

struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;  // true: value must be > min
  bool max_open = false;
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  // A length in metres that a scene can mean: positive, at most 1000 km (larger numbers overflow
  // the geometry's squares and grids long before they describe a body).
  static Range length() { return {0.0, 1e6, true, false}; }
  // A coordinate in metres, within 1000 km of the origin (for the same reason).
  static Range coordinate() { return {-1e6, 1e6, false, false}; }
  // A stiffness in pascals that a solid can have: at most 1e13 Pa (diamond's Young's modulus is
  // 1.2e12 Pa; 1e308 overflowed the Lamé parameters and was reported against nu).
  static Range modulus() { return {0.0, 1e13, true, false}; }
  static Range modulus_or_zero() { return {0.0, 1e13, false, false}; }
  // A mass density in kg/m³: from 1e-3 (below any aerogel) to 1e6 (fifty times osmium); 1e-308
  // underflowed the masses and IDA failed at t = 0 without a reason.
  static Range density() { return {1e-3, 1e6, false, false}; }
  // An acceleration in m/s² (each component): within 1e7 (a million g); 1e300 overflowed the
  // forces and IDA stopped at t = 0 with "tstop is behind current t".
  static Range acceleration() { return {-1e7, 1e7, false, false}; }
  // A speed in m/s (each component): within 1e5 (ten times the fastest projectile).
  static Range speed() { return {-1e5, 1e5, false, false}; }
  bool contains(double v) const;
  std::string describe() const;
};

class SceneFile;

class Section {
 public:
  // The dotted path of this table ("" for the root, "mesh", "zones.zone[2]").
  const std::string& path() const { return path_; }
  bool has(std::string_view key) const;
  // Whether the key's value came from a --set override rather than the file.
  bool overridden(std::string_view key) const;
  bool exists() const { return table_ != nullptr; }

  double number(std::string_view key, double fallback, Range range = {}) const;
  std::optional<double> number_opt(std::string_view key, Range range = {}) const;
  long integer(std::string_view key, long fallback, long min, long max) const;
  std::optional<long> integer_opt(std::string_view key, long min, long max) const;
  bool boolean(std::string_view key, bool fallback) const;
  std::string string(std::string_view key, const std::string& fallback,
                     const std::vector<std::string>& choices = {}) const;
  std::optional<std::string> string_opt(std::string_view key, const std::vector<std::string>& choices = {}) const;
  Eigen::Vector3d vec3(std::string_view key, const Eigen::Vector3d& fallback, Range range = {}) const;
  std::optional<Eigen::Vector3d> vec3_opt(std::string_view key, Range range = {}) const;
  std::vector<double> numbers(std::string_view key, Range range = {}) const;   // absent: empty
  std::vector<long> integers(std::string_view key, long min, long max) const;  // absent: empty
  std::vector<std::string> strings(std::string_view key) const;                // absent: empty
  // The keys of this table, in file order.
  std::vector<std::string> keys() const;
  // An int or a list of three ints (e.g. cells per axis).
  std::array<long, 3> int3(std::string_view key, std::array<long, 3> fallback, long min, long max) const;

  // A sub-table; an absent key gives an empty section (exists() false).
  Section table(std::string_view key) const;
  // An array of tables ([[zones.zone]]); absent gives an empty list.
  std::vector<Section> tables(std::string_view key) const;

  // `file:line: path.key: message`, with the line of the key if present, else of this table.
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;
  std::string where(std::string_view key) const;

 private:
  friend class SceneFile;
  Section(const SceneFile* file, const toml::table* table, std::string path)
      : file_(file), table_(table), path_(std::move(path)) {}
  // Marks the key as read; `leaf` keys (values, not tables) are recorded in queried_keys().
  const toml::node* get(std::string_view key, bool leaf = true) const;
  std::string full(std::string_view key) const;
  // Records the default a parser gave for the key (key_defaults()), and a number's range.
  void note_default(std::string_view key, std::string text) const;
  void note_range(std::string_view key, const Range& range) const;
  const SceneFile* file_ = nullptr;
  const toml::table* table_ = nullptr;
  std::string path_;
};

class SceneFile {
 public:
  // Reads a scene file and applies `--set key=value` overrides (dotted keys, TOML values; a
  // value that is not valid TOML is taken as a string).
  static SceneFile load(const std::string& path, const std::vector<std::string>& overrides = {});
  // A scene from text (`name` in messages; relative file names resolved against `directory`).
  static SceneFile parse(const std::string& text, const std::string& name,
                         const std::vector<std::string>& overrides = {}, const std::string& directory = "");
  SceneFile(SceneFile&&) noexcept;
  SceneFile& operator=(SceneFile&&) noexcept;
  ~SceneFile();

  Section root() const;
  const std::string& name() const { return name_; }
  // Directory of the scene file: relative file names in the scene are resolved against it.
  const std::string& directory() const { return directory_; }
  // A file the scene names, relative to its directory; recorded as one of its inputs.
  std::string resolve_path(const std::string& p) const;
  // The files the scene read (as written -> as resolved), and a digest of each as it is now: one
  // line "name<TAB>bytes<TAB>FNV-1a 64 of the content" per file, sorted ("missing" for a file that
  // is gone). A run file keeps it, so that a resume notices an input that changed.
  const std::map<std::string, std::string>& input_files() const { return inputs_; }
  std::string input_digests() const;
  // The scene as run (overrides applied), as TOML text.
  std::string text_as_run() const;
  // Throws on the first key (in file order) that no parser read.
  void check_unknown_keys() const;
  // Every dotted value key (array indices dropped, tables left out) that parsers asked for,
  // present or not.
  const std::set<std::string>& queried_keys() const { return queried_; }
  // The default each parser gave for a key it read with one (number, integer, boolean, string,
  // vec3, int3), as text: a key read in several places may carry several. docs/scenes.md's
  // default column is checked against them (Scene.EveryKeyReadByTheDemosIsDocumented).
  const std::map<std::string, std::set<std::string>>& key_defaults() const { return defaults_; }
  // The range each parser checked a number key against (Range::describe), likewise.
  const std::map<std::string, std::set<std::string>>& key_ranges() const { return ranges_; }

 private:
  friend class Section;
  SceneFile();
  std::unique_ptr<toml::table> root_;
  std::string name_, directory_;
  mutable std::set<const toml::node*> read_;
  mutable std::map<std::string, std::set<std::string>> asked_;  // table path -> keys asked for
  mutable std::set<std::string> queried_;
  mutable std::map<std::string, std::string> inputs_;
  mutable std::map<std::string, std::set<std::string>> defaults_, ranges_;
};

}  // namespace isochor
