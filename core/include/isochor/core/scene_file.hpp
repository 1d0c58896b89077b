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

#include "isochor/core/key_table.hpp"

namespace toml {
inline namespace v3 {
class node;
class table;
}  // namespace v3
}  // namespace toml

namespace isochor {

class SceneFile;

class Section {
 public:
  // The dotted path of this table ("" for the root, "mesh", "zones.zone[2]").
  const std::string& path() const { return path_; }
  bool has(std::string_view key) const;
  // Whether the key's value came from a --set override rather than the file.
  bool overridden(std::string_view key) const;
  bool exists() const { return table_ != nullptr; }

  // Typed reads. The key's row in the file's key table (KeyTable) gives its type, range and
  // default: `number(key)` falls back to the row's default; `number(key, fallback)` to a default the
  // parser works out (where the row gives it in words, "the body's"), which must equal the row's
  // where it has one. Reading a key that no row declares, or as another type, is a std::logic_error.
  double number(std::string_view key) const;
  double number(std::string_view key, double fallback) const;
  std::optional<double> number_opt(std::string_view key) const;
  long integer(std::string_view key) const;
  long integer(std::string_view key, long fallback) const;
  std::optional<long> integer_opt(std::string_view key) const;
  bool boolean(std::string_view key) const;
  bool boolean(std::string_view key, bool fallback) const;
  std::string string(std::string_view key) const;
  std::string string(std::string_view key, const std::string& fallback) const;
  std::optional<std::string> string_opt(std::string_view key) const;
  Eigen::Vector3d vec3(std::string_view key) const;
  Eigen::Vector3d vec3(std::string_view key, const Eigen::Vector3d& fallback) const;
  std::optional<Eigen::Vector3d> vec3_opt(std::string_view key) const;
  std::vector<double> numbers(std::string_view key) const;       // absent: empty
  std::vector<long> integers(std::string_view key) const;        // absent: empty
  std::vector<std::string> strings(std::string_view key) const;  // absent: empty
  // The keys of this table, in file order.
  std::vector<std::string> keys() const;
  // An int or a list of three ints (e.g. cells per axis).
  std::array<long, 3> int3(std::string_view key) const;
  std::array<long, 3> int3(std::string_view key, std::array<long, 3> fallback) const;

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
  // Marks the key as read (check_unknown_keys).
  const toml::node* get(std::string_view key) const;
  std::string full(std::string_view key) const;
  // The key's row; throws std::logic_error when none declares it or declares another kind.
  const KeySpec& spec(std::string_view key, KeyKind kind) const;
  // The row's default; throws std::logic_error when it has none.
  const KeyDefault& declared_default(std::string_view key, const KeySpec& spec) const;
  // Throws std::logic_error when the parser's default differs from the row's.
  void check_default(std::string_view key, const KeySpec& spec, bool same) const;
  std::optional<double> number_in(std::string_view key, const Range& range) const;
  std::optional<long> integer_in(std::string_view key, long min, long max) const;
  std::vector<double> numbers_in(std::string_view key, const Range& range) const;
  std::vector<long> integers_in(std::string_view key, long min, long max) const;
  const SceneFile* file_ = nullptr;
  const toml::table* table_ = nullptr;
  std::string path_;
};

class SceneFile {
 public:
  // Reads a scene file and applies `--set key=value` overrides (dotted keys, TOML values; a
  // value that is not valid TOML is taken as a string).
  // `keys` declares what the file may hold (scene_keys() for a scene).
  static SceneFile load(const std::string& path, const std::vector<std::string>& overrides = {},
                        const KeyTable& keys = scene_keys());
  // A scene from text (`name` in messages; relative file names resolved against `directory`).
  static SceneFile parse(const std::string& text, const std::string& name,
                         const std::vector<std::string>& overrides = {}, const std::string& directory = "",
                         const KeyTable& keys = scene_keys());
  SceneFile(SceneFile&&) noexcept;
  SceneFile& operator=(SceneFile&&) noexcept;
  ~SceneFile();

  Section root() const;
  const KeyTable& keys() const { return *keys_; }
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

 private:
  friend class Section;
  SceneFile();
  std::unique_ptr<toml::table> root_;
  std::string name_, directory_;
  mutable std::set<const toml::node*> read_;
  mutable std::map<std::string, std::set<std::string>> asked_;  // table path -> keys asked for
  mutable std::map<std::string, std::string> inputs_;
  const KeyTable* keys_ = nullptr;
};

}  // namespace isochor
