// The keys a TOML input (a scene, a study) may hold, each declared once: its type, unit, default,
// range and documentation line. The parsers take defaults and checks from here (Section), and the
// key tables of docs/scenes.md and docs/studies.md are generated from here (`make docs`;
// Scene.TheDocsKeyTablesAreGeneratedFromTheKeyTable fails when they differ).
#pragma once
#include <Eigen/Core>
#include <array>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace isochor {

struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;  // true: value must be > min
  bool max_open = false;
  static constexpr Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static constexpr Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static constexpr Range closed(double a, double b) { return {a, b, false, false}; }
  // A length in metres that a scene can mean: positive, at most 1000 km (larger numbers overflow
  // the geometry's squares and grids long before they describe a body).
  static constexpr Range length() { return {0.0, 1e6, true, false}; }
  // A coordinate in metres, within 1000 km of the origin (for the same reason).
  static constexpr Range coordinate() { return {-1e6, 1e6, false, false}; }
  // A stiffness in pascals that a solid can have: at most 1e13 Pa (diamond's Young's modulus is
  // 1.2e12 Pa; 1e308 overflowed the Lamé parameters and was reported against nu).
  static constexpr Range modulus() { return {0.0, 1e13, true, false}; }
  static constexpr Range modulus_or_zero() { return {0.0, 1e13, false, false}; }
  // A mass density in kg/m³: from 1e-3 (below any aerogel) to 1e6 (fifty times osmium); 1e-308
  // underflowed the masses and IDA failed at t = 0 without a reason.
  static constexpr Range density() { return {1e-3, 1e6, false, false}; }
  // An acceleration in m/s² (each component): within 1e7 (a million g); 1e300 overflowed the
  // forces and IDA stopped at t = 0 with "tstop is behind current t".
  static constexpr Range acceleration() { return {-1e7, 1e7, false, false}; }
  // A speed in m/s (each component): within 1e5 (ten times the fastest projectile).
  static constexpr Range speed() { return {-1e5, 1e5, false, false}; }
  bool contains(double v) const;
  std::string describe() const;
  // As docs/scenes.md writes it: "> 0", "in (0, 10¹³]", "" for any finite number.
  std::string symbols() const;
};

enum class KeyKind {
  number,    // a finite number in `range`
  integer,   // an integer in [min, max]
  boolean,   // true or false
  string,    // a string, one of `choices` when they are given
  vec3,      // [x, y, z], each in `range`
  int3,      // an integer or [nx, ny, nz], each in [min, max]
  numbers,   // a list of numbers, each in `range`
  integers,  // a list of integers, each in [min, max]
  strings,   // a list of strings
  table,     // a table whose keys are declared below it
  tables,    // an array of tables ([[name]])
};

// One key. `name` is dotted, array indices dropped; a segment in angle brackets (`<zone>`) stands
// for any one name (the last one also for a quoted dotted name).
struct KeySpec {
  std::string_view name;
  KeyKind kind;
  // A table whose keys are those of another row's (`select`: a selection, declared once as
  // `select.*`; `boundary`: a driver).
  std::string_view like = {};
  std::string_view unit = "–";
  // The default the parser falls back to, as a TOML value ("1e4", "[0, 0, 0]", "\"cnh\"", "true");
  // empty where there is none or it depends on other keys.
  std::string_view fallback = {};
  // The default as the docs say it, where `fallback` alone does not ("0 (off)", "the body's").
  std::string_view shown = {};
  Range range = {};               // number, vec3, numbers
  long min = 0, max = 0;          // integer, int3, integers
  std::string_view choices = {};  // string: the words allowed, space-separated (empty: any)
  std::string_view type = {};     // the docs' type cell where the kind's own words do not fit
  std::string_view doc = {};
};

// A key's default, parsed from KeySpec::fallback.
struct KeyDefault {
  bool present = false;
  double number = 0;
  long integer = 0;
  bool boolean = false;
  std::string string;
  Eigen::Vector3d vec3 = Eigen::Vector3d::Zero();
  std::array<long, 3> int3{};
};

class KeyTable {
 public:
  // `source` names where the rows are written (for messages). Throws std::logic_error on a row
  // whose default does not parse, is of another kind or outside its range, or a name given twice.
  KeyTable(std::string source, std::vector<KeySpec> keys);
  const std::vector<KeySpec>& keys() const { return keys_; }
  const std::string& source() const { return source_; }
  // The row of a dotted key (indices dropped); nullptr when none declares it.
  const KeySpec* find(std::string_view dotted) const;
  const KeyDefault& fallback(const KeySpec& spec) const { return defaults_.at(&spec); }
  // The markdown rows (key, type, unit, default, meaning) of the keys whose first segment is one
  // of `groups`, in table order, with the header.
  std::string markdown(const std::vector<std::string>& groups) const;
  // `text` with every generated table replaced: a line `<!-- keys: GROUP ... -->` is followed by
  // the table of those groups (the lines that start with `|` up to the next other line).
  std::string update_docs(const std::string& text) const;

 private:
  std::string source_;
  std::vector<KeySpec> keys_;
  std::map<std::string, const KeySpec*, std::less<>> exact_;
  std::map<const KeySpec*, KeyDefault> defaults_;
};

// The keys of a scene file (core/src/scene_keys.cpp).
const KeyTable& scene_keys();

}  // namespace isochor
