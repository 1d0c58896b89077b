#include "isochor/core/input_file.hpp"
#include "isochor/core/scene_file.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {

constexpr const char* kOverride = "--set";

// A scene's strings are paths, names and choices: none is longer than a path may be (PATH_MAX),
// and a longer one is refused before it is used.
constexpr std::size_t kMaxStringBytes = 4096;

std::string too_long(const std::string& v) {
  return "expected a string of at most " + std::to_string(kMaxStringBytes) +
         " bytes (a path, a name or a choice), got " + std::to_string(v.size()) + " bytes";
}

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Whether a value came from a --set override rather than a file.
bool from_override(const toml::node* n) { return n && n->source().path && *n->source().path == kOverride; }

std::string source_of(const toml::node* n, const std::string& fallback_file) {
  if (from_override(n)) return kOverride;
  std::string file = (n && n->source().path) ? *n->source().path : fallback_file;
  long line = n ? static_cast<long>(n->source().begin.line) : 0;
  return file + ":" + std::to_string(line);
}

std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "a list";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a number";
    case toml::node_type::boolean:
      return "a boolean";
    default:
      return "a date or time";
  }
}

std::string strip_indices(const std::string& path) {
  std::string out;
  bool skip = false;
  for (char c : path) {
    if (c == '[') skip = true;
    if (!skip) out += c;
    if (c == ']') skip = false;
  }
  return out;
}

// A TOML integer or float as a double; nullopt for any other node.
std::optional<double> number_of(const toml::node& n) {
  if (auto i = n.as_integer()) return static_cast<double>(i->get());
  if (auto f = n.as_floating_point()) return f->get();
  return std::nullopt;
}

}  // namespace

// ---------------------------------------------------------------- Section

std::string Section::full(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

const toml::node* Section::get(std::string_view key) const {
  file_->asked_[path_].insert(std::string(key));
  if (!table_) return nullptr;
  const toml::node* n = table_->get(key);
  if (n) file_->read_.insert(n);
  return n;
}

bool Section::has(std::string_view key) const {
  file_->asked_[path_].insert(std::string(key));
  return table_ && table_->contains(key);
}

bool Section::overridden(std::string_view key) const { return from_override(table_ ? table_->get(key) : nullptr); }

std::string Section::where(std::string_view key) const {
  const toml::node* n = table_ ? table_->get(key) : nullptr;
  if (!n) n = table_;
  if (from_override(n)) return std::string(kOverride) + " " + full(key);
  return source_of(n, file_->name_) + ": " + full(key);
}

void Section::fail(std::string_view key, const std::string& message) const { throw Error(where(key) + ": " + message); }

const KeySpec& Section::spec(std::string_view key, KeyKind kind) const {
  const std::string name = strip_indices(full(key));
  const KeySpec* s = file_->keys_->find(name);
  if (!s) throw std::logic_error(name + " is read but not declared in " + file_->keys_->source());
  if (s->kind != kind)
    throw std::logic_error(name + " is read as another type than " + file_->keys_->source() + " declares");
  return *s;
}

const KeyDefault& Section::declared_default(std::string_view key, const KeySpec& spec) const {
  const KeyDefault& d = file_->keys_->fallback(spec);
  if (!d.present)
    throw std::logic_error(strip_indices(full(key)) + " is read with the default of " + file_->keys_->source() +
                           ", which gives none");
  return d;
}

void Section::check_default(std::string_view key, const KeySpec& spec, bool same) const {
  if (file_->keys_->fallback(spec).present && !same)
    throw std::logic_error(strip_indices(full(key)) + ": the parser's default is not the one " +
                           file_->keys_->source() + " declares (" + std::string(spec.fallback) + ")");
}

std::optional<double> Section::number_in(std::string_view key, const Range& range) const {
  const toml::node* n = get(key);
  if (!n) return std::nullopt;
  const std::optional<double> number = number_of(*n);
  if (!number) fail(key, "expected " + range.describe() + ", got " + type_name(*n));
  const double v = *number;
  if (!std::isfinite(v) || !range.contains(v)) fail(key, "expected " + range.describe() + ", got " + fmt(v));
  return v;
}

std::optional<double> Section::number_opt(std::string_view key) const {
  return number_in(key, spec(key, KeyKind::number).range);
}

double Section::number(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::number);
  if (auto v = number_in(key, s.range)) return *v;
  return declared_default(key, s).number;
}

double Section::number(std::string_view key, double fallback) const {
  const KeySpec& s = spec(key, KeyKind::number);
  check_default(key, s, file_->keys_->fallback(s).number == fallback);
  return number_in(key, s.range).value_or(fallback);
}

std::optional<long> Section::integer_in(std::string_view key, long min, long max) const {
  const toml::node* n = get(key);
  if (!n) return std::nullopt;
  std::string expect = "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  auto i = n->as_integer();
  if (!i) fail(key, "expected " + expect + ", got " + type_name(*n));
  long v = static_cast<long>(i->get());
  if (v < min || v > max) fail(key, "expected " + expect + ", got " + std::to_string(v));
  return v;
}

std::optional<long> Section::integer_opt(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::integer);
  return integer_in(key, s.min, s.max);
}

long Section::integer(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::integer);
  if (auto v = integer_in(key, s.min, s.max)) return *v;
  return declared_default(key, s).integer;
}

long Section::integer(std::string_view key, long fallback) const {
  const KeySpec& s = spec(key, KeyKind::integer);
  check_default(key, s, file_->keys_->fallback(s).integer == fallback);
  return integer_in(key, s.min, s.max).value_or(fallback);
}

bool Section::boolean(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::boolean);
  if (!has(key)) return declared_default(key, s).boolean;
  return boolean(key, file_->keys_->fallback(s).boolean);
}

bool Section::boolean(std::string_view key, bool fallback) const {
  const KeySpec& s = spec(key, KeyKind::boolean);
  check_default(key, s, file_->keys_->fallback(s).boolean == fallback);
  const toml::node* n = get(key);
  if (!n) return fallback;
  auto b = n->as_boolean();
  if (!b) fail(key, "expected true or false, got " + type_name(*n));
  return b->get();
}

std::optional<std::string> Section::string_opt(std::string_view key) const {
  const KeySpec& spec_ = spec(key, KeyKind::string);
  std::vector<std::string> choices;
  std::istringstream words{std::string(spec_.choices)};
  for (std::string w; words >> w;) choices.push_back(w);
  const toml::node* n = get(key);
  if (!n) return std::nullopt;
  std::string expect = "a string";
  if (!choices.empty()) {
    expect = "one of";
    for (std::size_t i = 0; i < choices.size(); ++i) expect += (i ? ", \"" : " \"") + choices[i] + "\"";
  }
  auto s = n->as_string();
  if (!s) fail(key, "expected " + expect + ", got " + type_name(*n));
  std::string v = s->get();
  if (v.size() > kMaxStringBytes) fail(key, too_long(v));
  if (!choices.empty() && std::find(choices.begin(), choices.end(), v) == choices.end())
    fail(key, "expected " + expect + ", got \"" + v + "\"");
  return v;
}

std::string Section::string(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::string);
  if (auto v = string_opt(key)) return *v;
  return declared_default(key, s).string;
}

std::string Section::string(std::string_view key, const std::string& fallback) const {
  const KeySpec& s = spec(key, KeyKind::string);
  check_default(key, s, file_->keys_->fallback(s).string == fallback);
  return string_opt(key).value_or(fallback);
}

std::vector<double> Section::numbers_in(std::string_view key, const Range& range) const {
  const toml::node* n = get(key);
  if (!n) return {};
  std::string expect = "a list of numbers, each " + range.describe();
  auto a = n->as_array();
  if (!a) fail(key, "expected " + expect + ", got " + type_name(*n));
  std::vector<double> out;
  for (const toml::node& e : *a) {
    const std::optional<double> number = number_of(e);
    if (!number) fail(key, "expected " + expect + ", got an element that is " + type_name(e));
    const double v = *number;
    if (!std::isfinite(v) || !range.contains(v)) fail(key, "expected " + expect + ", got " + fmt(v));
    out.push_back(v);
  }
  return out;
}

std::vector<double> Section::numbers(std::string_view key) const {
  return numbers_in(key, spec(key, KeyKind::numbers).range);
}

std::vector<std::string> Section::strings(std::string_view key) const {
  spec(key, KeyKind::strings);
  const toml::node* n = get(key);
  if (!n) return {};
  auto a = n->as_array();
  if (!a) fail(key, "expected a list of strings, got " + type_name(*n));
  std::vector<std::string> out;
  for (const toml::node& e : *a) {
    auto s = e.as_string();
    if (!s) fail(key, "expected a list of strings, got an element that is " + type_name(e));
    if (s->get().size() > kMaxStringBytes) fail(key, too_long(s->get()));
    out.push_back(s->get());
  }
  return out;
}

std::vector<std::string> Section::keys() const {
  std::vector<std::pair<std::size_t, std::string>> k;
  if (table_)
    for (const auto& [key, node] : *table_) k.emplace_back(node.source().begin.line, std::string(key.str()));
  std::sort(k.begin(), k.end());
  std::vector<std::string> out;
  for (auto& [line, key] : k) out.push_back(key);
  return out;
}

std::vector<long> Section::integers_in(std::string_view key, long min, long max) const {
  const toml::node* n = get(key);
  if (!n) return {};
  std::string expect = "a list of integers in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  auto a = n->as_array();
  if (!a) fail(key, "expected " + expect + ", got " + type_name(*n));
  std::vector<long> out;
  for (const toml::node& e : *a) {
    auto i = e.as_integer();
    if (!i) fail(key, "expected " + expect + ", got an element that is " + type_name(e));
    long v = static_cast<long>(i->get());
    if (v < min || v > max) fail(key, "expected " + expect + ", got " + std::to_string(v));
    out.push_back(v);
  }
  return out;
}

std::vector<long> Section::integers(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::integers);
  return integers_in(key, s.min, s.max);
}

std::optional<Eigen::Vector3d> Section::vec3_opt(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::vec3);
  if (!has(key)) {
    get(key);
    return std::nullopt;
  }
  std::vector<double> v = numbers_in(key, s.range);
  if (v.size() != 3) fail(key, "expected a list of 3 numbers, got " + std::to_string(v.size()));
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Vector3d Section::vec3(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::vec3);
  if (auto v = vec3_opt(key)) return *v;
  return declared_default(key, s).vec3;
}

Eigen::Vector3d Section::vec3(std::string_view key, const Eigen::Vector3d& fallback) const {
  const KeySpec& s = spec(key, KeyKind::vec3);
  check_default(key, s, file_->keys_->fallback(s).vec3 == fallback);
  return vec3_opt(key).value_or(fallback);
}

std::array<long, 3> Section::int3(std::string_view key) const {
  const KeySpec& s = spec(key, KeyKind::int3);
  if (!has(key)) return declared_default(key, s).int3;
  return int3(key, file_->keys_->fallback(s).int3);
}

std::array<long, 3> Section::int3(std::string_view key, std::array<long, 3> fallback) const {
  const KeySpec& s = spec(key, KeyKind::int3);
  check_default(key, s, file_->keys_->fallback(s).int3 == fallback);
  const long min = s.min, max = s.max;
  const toml::node* n = get(key);
  if (!n) return fallback;
  if (n->is_integer()) {
    const long v = *integer_in(key, min, max);
    return {v, v, v};
  }
  if (!n->is_array())
    fail(key, "expected an integer or a list of 3 integers in [" + std::to_string(min) + ", " + std::to_string(max) +
                  "], got " + type_name(*n));
  std::vector<long> v = integers_in(key, min, max);
  if (v.size() != 3)
    fail(key, "expected an integer or a list of 3 integers, got a list of " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

Section Section::table(std::string_view key) const {
  spec(key, KeyKind::table);
  const toml::node* n = get(key);
  if (!n) return Section(file_, nullptr, full(key));
  auto t = n->as_table();
  if (!t) fail(key, "expected a table, got " + type_name(*n));
  return Section(file_, t, full(key));
}

std::vector<Section> Section::tables(std::string_view key) const {
  spec(key, KeyKind::tables);
  const toml::node* n = get(key);
  std::vector<Section> out;
  if (!n) return out;
  auto a = n->as_array();
  if (!a || !a->is_array_of_tables())
    fail(key, "expected a list of tables ([[" + full(key) + "]]), got " + type_name(*n));
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::table* t = (*a)[i].as_table();
    file_->read_.insert(t);
    out.push_back(Section(file_, t, full(key) + "[" + std::to_string(i) + "]"));
  }
  return out;
}

// ---------------------------------------------------------------- SceneFile

SceneFile::SceneFile() : root_(std::make_unique<toml::table>()) {}
SceneFile::SceneFile(SceneFile&&) noexcept = default;
SceneFile& SceneFile::operator=(SceneFile&&) noexcept = default;
SceneFile::~SceneFile() = default;

Section SceneFile::root() const { return Section(this, root_.get(), ""); }

std::string SceneFile::resolve_path(const std::string& p) const {
  std::filesystem::path path(p);
  const std::string resolved = path.is_absolute() || directory_.empty()
                                   ? p
                                   : (std::filesystem::path(directory_) / path).lexically_normal().string();
  inputs_[p] = resolved;
  return resolved;
}

std::string SceneFile::input_digests() const {
  std::string out;
  for (const auto& [name, path] : inputs_) {
    std::ifstream in(path, std::ios::binary);
    std::uint64_t hash = 1469598103934665603ull, bytes = 0;
    char buf[1 << 16];
    while (in) {
      in.read(buf, sizeof buf);
      const std::streamsize got = in.gcount();
      for (std::streamsize i = 0; i < got; ++i) hash = (hash ^ static_cast<unsigned char>(buf[i])) * 1099511628211ull;
      bytes += static_cast<std::uint64_t>(got);
    }
    char line[64];
    std::snprintf(line, sizeof line, "\t%llu\t%016llx\n", static_cast<unsigned long long>(bytes),
                  static_cast<unsigned long long>(hash));
    out += name + (std::filesystem::is_regular_file(path) ? std::string(line) : std::string("\tmissing\n"));
  }
  return out;
}

namespace {

// toml++ makes a table for each part of a dotted key and recurses through them: a key of 50,000
// parts overflowed the stack. A scene's keys have a few parts, so a line whose keys have more
// than this many in all is refused before it is parsed.
constexpr int kMaxDottedParts = 256;

bool digit_at(const std::string& text, std::size_t i) {
  return i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]));
}

bool run_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '+' || c == '.';
}

bool starts(const std::string& text, std::size_t i, const char* what) { return text.compare(i, 3, what) == 0; }

// Counts, line by line and outside strings and comments, the dots that join key parts: every dot
// but a number's (the one dot between digits in a run of key or number characters).
void check_dotted_keys(const std::string& text, const std::string& name) {
  enum class In { plain, basic, literal, ml_basic, ml_literal, comment } in = In::plain;
  std::size_t line = 1;
  int dots = 0, run_dots = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      dots = run_dots = 0;
      if (in == In::comment || in == In::basic || in == In::literal) in = In::plain;
      continue;
    }
    const bool escape = c == '\\' && i + 1 < text.size() && text[i + 1] != '\n';
    switch (in) {
      case In::comment:
        break;
      case In::basic:
        if (escape)
          ++i;
        else if (c == '"')
          in = In::plain;
        break;
      case In::literal:
        if (c == '\'') in = In::plain;
        break;
      case In::ml_basic:
        if (escape)
          ++i;
        else if (starts(text, i, "\"\"\""))
          in = In::plain, i += 2;
        break;
      case In::ml_literal:
        if (starts(text, i, "'''")) in = In::plain, i += 2;
        break;
      case In::plain:
        if (!run_char(c)) run_dots = 0;
        if (c == '#')
          in = In::comment;
        else if (starts(text, i, "\"\"\""))
          in = In::ml_basic, i += 2;
        else if (starts(text, i, "'''"))
          in = In::ml_literal, i += 2;
        else if (c == '"')
          in = In::basic;
        else if (c == '\'')
          in = In::literal;
        else if (c == '.' && (++run_dots > 1 || i == 0 || !digit_at(text, i - 1) || !digit_at(text, i + 1)) &&
                 ++dots >= kMaxDottedParts)
          throw Error(name + ":" + std::to_string(line) + ": keys of more than " + std::to_string(kMaxDottedParts) +
                      " dotted parts (expected a scene's tables and keys, a few levels deep)");
        break;
    }
  }
}

}  // namespace

SceneFile SceneFile::load(const std::string& path, const std::vector<std::string>& overrides, const KeyTable& keys) {
  const std::string text = read_input_file(path, "a scene file in TOML", input_limits::kScene);
  return parse(text, path, overrides, std::filesystem::path(path).parent_path().string(), keys);
}

SceneFile SceneFile::parse(const std::string& text, const std::string& name, const std::vector<std::string>& overrides,
                           const std::string& directory, const KeyTable& keys) {
  SceneFile f;
  f.keys_ = &keys;
  f.name_ = name;
  f.directory_ = directory;
  check_dotted_keys(text, name);
  try {
    *f.root_ = toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    throw Error(name + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()) +
                " (expected valid TOML)");
  }
  for (const std::string& o : overrides) {
    auto eq = o.find('=');
    if (eq == std::string::npos || eq == 0)
      throw Error(std::string(kOverride) + " " + o + ": expected key=value, e.g. integrator.rtol=1e-6");
    std::string key = o.substr(0, eq), value = o.substr(eq + 1);
    check_dotted_keys(o, std::string(kOverride) + " " + key.substr(0, 64));
    toml::table parsed;
    try {
      parsed = toml::parse(key + " = " + value, std::string_view(kOverride));
    } catch (const toml::parse_error&) {
      try {  // a bare word: take it as a string
        std::ostringstream quoted;
        quoted << toml::value<std::string>(value);
        parsed = toml::parse(key + " = " + quoted.str(), std::string_view(kOverride));
      } catch (const toml::parse_error& e) {
        throw Error(std::string(kOverride) + " " + o + ": " + std::string(e.description()) + " (expected key=value)");
      }
    }
    // Walk the single dotted path of `parsed` and put its leaf into the scene.
    toml::table* dst = f.root_.get();
    toml::table* src = &parsed;
    std::string walked;
    while (true) {
      auto it = src->begin();
      std::string k(it->first.str());
      walked += (walked.empty() ? "" : ".") + k;
      if (auto sub = it->second.as_table()) {
        toml::node* d = dst->get(k);
        if (!d) d = &dst->insert_or_assign(k, toml::table{}).first->second;
        if (!d->is_table())
          throw Error(std::string(kOverride) + " " + o + ": " + walked + " is " + type_name(*d) + " in " + name +
                      ", expected a table");
        dst = d->as_table();
        src = sub;
        continue;
      }
      dst->insert_or_assign(k, std::move(it->second));
      break;
    }
  }
  return f;
}

std::string SceneFile::text_as_run() const {
  std::ostringstream s;
  s << *root_;
  return s.str();
}

void SceneFile::check_unknown_keys() const {
  struct Unknown {
    const toml::node* node;
    std::string path, table_path, key;
  };
  std::vector<Unknown> unknown;
  auto walk = [&](auto&& self, const toml::table& t, const std::string& path) -> void {
    for (const auto& [k, n] : t) {
      std::string key(k.str());
      std::string p = path.empty() ? key : path + "." + key;
      if (!read_.count(&n)) {
        unknown.push_back({&n, p, path, key});
        continue;
      }
      if (auto sub = n.as_table()) self(self, *sub, p);
      if (auto arr = n.as_array())
        for (std::size_t i = 0; i < arr->size(); ++i)
          if (auto sub2 = (*arr)[i].as_table()) self(self, *sub2, p + "[" + std::to_string(i) + "]");
    }
  };
  walk(walk, *root_, "");
  if (unknown.empty()) return;
  // The first in file order; overrides last.
  auto line = [](const Unknown& u) {
    bool ov = u.node->source().path && *u.node->source().path == kOverride;
    return std::make_pair(ov ? 1 : 0, static_cast<long>(u.node->source().begin.line));
  };
  const Unknown& u = *std::min_element(unknown.begin(), unknown.end(),
                                       [&](const Unknown& a, const Unknown& b) { return line(a) < line(b); });
  std::string known;
  auto it = asked_.find(u.table_path);
  if (it != asked_.end())
    for (const std::string& k : it->second) known += (known.empty() ? "" : ", ") + k;
  std::string msg = "unknown key";
  if (!known.empty()) msg += " (expected one of: " + known + ")";
  std::string loc = (u.node->source().path && *u.node->source().path == kOverride)
                        ? std::string(kOverride) + " " + u.path
                        : source_of(u.node, name_) + ": " + u.path;
  throw Error(loc + ": " + msg);
}

}  // namespace isochor
