#include "isochor/core/key_table.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace isochor {

namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// A number as the docs write it: powers of ten from 10⁴ (and below 10⁻³) as 10 with a superscript,
// a minus sign as −.
std::string doc_number(double v) {
  if (std::isinf(v)) return v > 0 ? "∞" : "−∞";
  std::string sign = v < 0 ? "−" : "";
  const double a = std::fabs(v);
  const double e = std::round(std::log10(a));
  if (a > 0 && (e >= 4 || e <= -4) && std::fabs(a - std::pow(10.0, e)) <= 1e-12 * a) {
    static const char* digits[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
    std::string out = sign + "10";
    if (e < 0) out += "⁻";
    for (char c : std::to_string(static_cast<long>(std::fabs(e)))) out += digits[c - '0'];
    return out;
  }
  return sign + fmt(a);
}

std::vector<std::string> segments(std::string_view dotted) {
  std::vector<std::string> out(1);
  for (char c : dotted) {
    if (c == '.')
      out.emplace_back();
    else
      out.back() += c;
  }
  return out;
}

// `<zone>` matches one segment, or, last, the segments left: a name may be a quoted dotted key
// (`method.sweep."integrator.rtol"`).
bool matches(std::string_view pattern, const std::vector<std::string>& name) {
  const std::vector<std::string> p = segments(pattern);
  if (name.size() < p.size() || (name.size() > p.size() && p.back().front() != '<')) return false;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p[i] != name[i] && !(p[i].size() > 2 && p[i].front() == '<' && p[i].back() == '>')) return false;
  return true;
}

std::string join(const std::vector<std::string>& s, std::size_t from, std::size_t to) {
  std::string out;
  for (std::size_t i = from; i < to; ++i) out += (i > from ? "." : "") + s[i];
  return out;
}

bool is_range_kind(KeyKind k) { return k == KeyKind::number || k == KeyKind::vec3 || k == KeyKind::numbers; }
bool is_integer_kind(KeyKind k) { return k == KeyKind::integer || k == KeyKind::int3 || k == KeyKind::integers; }

// An integer as the docs write it (a minus sign as −).
std::string doc_integer(long v) { return v < 0 ? "−" + std::to_string(-v) : std::to_string(v); }

std::string integer_words(long min, long max) {
  const long big = 1000000000L;
  if (min <= -big && max >= big) return "";
  if (max >= big) return " ≥ " + doc_integer(min);
  return " in [" + doc_integer(min) + ", " + doc_integer(max) + "]";
}

std::string type_cell(const KeySpec& k) {
  if (!k.type.empty()) return std::string(k.type);
  const std::string range = k.range.symbols().empty() ? "" : " " + k.range.symbols();
  const std::string each = k.range.symbols().empty() ? "" : ", each " + k.range.symbols();
  switch (k.kind) {
    case KeyKind::number:
      return "number" + range;
    case KeyKind::integer:
      return "int" + integer_words(k.min, k.max);
    case KeyKind::boolean:
      return "bool";
    case KeyKind::string:
      return "string";
    case KeyKind::vec3:
      return "[x, y, z]" + each;
    case KeyKind::int3:
      return "int or [nx, ny, nz]" + integer_words(k.min, k.max);
    case KeyKind::numbers:
      return "[number]" + each;
    case KeyKind::integers:
      return "[int]" + integer_words(k.min, k.max);
    case KeyKind::strings:
      return "[string]";
    case KeyKind::table:
      if (k.like == "select") return "selection";
      return k.like.empty() ? "table" : "table (the keys of `" + std::string(k.like) + "`)";
    case KeyKind::tables:
      return "array of tables";
  }
  return "";
}

std::string default_cell(const KeySpec& k) {
  if (!k.shown.empty()) return std::string(k.shown);
  if (k.fallback.empty()) return "–";
  if (k.kind == KeyKind::string) return "`" + std::string(k.fallback) + "`";
  return std::string(k.fallback);
}

std::string escape_pipes(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

// Parses and checks a row's default; throws std::logic_error naming the row.
KeyDefault parse_default(const std::string& source, const KeySpec& k) {
  KeyDefault d;
  if (k.fallback.empty()) return d;
  const auto bad = [&](const std::string& what) {
    return std::logic_error(source + ": " + std::string(k.name) + ": default " + std::string(k.fallback) + " " + what);
  };
  toml::table t;
  try {
    t = toml::parse("v = " + std::string(k.fallback));
  } catch (const toml::parse_error&) {
    throw bad("is not a TOML value");
  }
  const toml::node& v = *t.get("v");
  const auto number_of = [&](const toml::node& n) {
    if (auto i = n.as_integer()) return static_cast<double>(i->get());
    if (auto f = n.as_floating_point()) return f->get();
    throw bad("is not a number");
  };
  const auto integer_of = [&](const toml::node& n) {
    auto i = n.as_integer();
    if (!i) throw bad("is not an integer");
    if (i->get() < k.min || i->get() > k.max) throw bad("is outside the row's range");
    return static_cast<long>(i->get());
  };
  d.present = true;
  switch (k.kind) {
    case KeyKind::number:
      d.number = number_of(v);
      if (!k.range.contains(d.number)) throw bad("is outside the row's range");
      break;
    case KeyKind::integer:
      d.integer = integer_of(v);
      break;
    case KeyKind::boolean:
      if (!v.is_boolean()) throw bad("is not true or false");
      d.boolean = v.as_boolean()->get();
      break;
    case KeyKind::string:
      if (!v.is_string()) throw bad("is not a string");
      d.string = v.as_string()->get();
      break;
    case KeyKind::vec3: {
      auto a = v.as_array();
      if (!a || a->size() != 3) throw bad("is not a list of 3 numbers");
      for (int i = 0; i < 3; ++i) {
        d.vec3[i] = number_of(*a->get(i));
        if (!k.range.contains(d.vec3[i])) throw bad("is outside the row's range");
      }
      break;
    }
    case KeyKind::int3:
      if (auto a = v.as_array()) {
        if (a->size() != 3) throw bad("is not an integer or a list of 3");
        for (int i = 0; i < 3; ++i) d.int3[i] = integer_of(*a->get(i));
      } else {
        d.int3.fill(integer_of(v));
      }
      break;
    default:  // lists and tables: their default is written for the docs only
      break;
  }
  return d;
}

}  // namespace

bool Range::contains(double v) const {
  if (std::isnan(v)) return false;
  if (min_open ? !(v > min) : !(v >= min)) return false;
  if (max_open ? !(v < max) : !(v <= max)) return false;
  return true;
}

std::string Range::describe() const {
  bool lo = std::isfinite(min), hi = std::isfinite(max);
  if (lo && hi)
    return std::string("a number in ") + (min_open ? "(" : "[") + fmt(min) + ", " + fmt(max) + (max_open ? ")" : "]");
  if (lo) return std::string("a number ") + (min_open ? "> " : ">= ") + fmt(min);
  if (hi) return std::string("a number ") + (max_open ? "< " : "<= ") + fmt(max);
  return "a finite number";
}

std::string Range::symbols() const {
  const bool lo = std::isfinite(min), hi = std::isfinite(max);
  if (lo && hi)
    return std::string("in ") + (min_open ? "(" : "[") + doc_number(min) + ", " + doc_number(max) +
           (max_open ? ")" : "]");
  if (lo) return (min_open ? "> " : "≥ ") + doc_number(min);
  if (hi) return (max_open ? "< " : "≤ ") + doc_number(max);
  return "";
}

KeyTable::KeyTable(std::string source, std::vector<KeySpec> keys) : source_(std::move(source)), keys_(std::move(keys)) {
  for (const KeySpec& k : keys_) {
    if (!exact_.emplace(std::string(k.name), &k).second)
      throw std::logic_error(source_ + ": " + std::string(k.name) + " is declared twice");
    if (is_integer_kind(k.kind) && k.min > k.max)
      throw std::logic_error(source_ + ": " + std::string(k.name) + ": min above max");
    if (!is_range_kind(k.kind) && (std::isfinite(k.range.min) || std::isfinite(k.range.max)))
      throw std::logic_error(source_ + ": " + std::string(k.name) + ": a range on a key that is not a number");
    defaults_[&k] = parse_default(source_, k);
  }
}

const KeySpec* KeyTable::find(std::string_view dotted) const {
  if (auto it = exact_.find(dotted); it != exact_.end()) return it->second;
  const std::vector<std::string> name = segments(dotted);
  for (const KeySpec& k : keys_)
    if (k.name.find('<') != std::string_view::npos && matches(k.name, name)) return &k;
  // A key inside a table declared `like` another: that one's row (`zones.zone.select.kind` is
  // `select.kind`).
  for (std::size_t n = name.size() - 1; n >= 1; --n) {
    const KeySpec* above = find(join(name, 0, n));
    if (above && !above->like.empty()) return find(std::string(above->like) + "." + join(name, n, name.size()));
  }
  return nullptr;
}

std::string KeyTable::markdown(const std::vector<std::string>& groups) const {
  std::string out = "| key | type | unit | default | meaning |\n|---|---|---|---|---|\n";
  for (const KeySpec& k : keys_) {
    const std::string first = segments(k.name).front();
    bool in = false;
    for (const std::string& g : groups) in = in || g == first;
    if (!in) continue;
    out += "| `" + std::string(k.name) + "` | " + type_cell(k) + " | " + std::string(k.unit) + " | " +
           escape_pipes(default_cell(k)) + " | " + escape_pipes(k.doc) + " |\n";
  }
  return out;
}

std::string KeyTable::update_docs(const std::string& text) const {
  static const std::string marker = "<!-- keys:";
  std::istringstream in(text);
  std::string out, line;
  bool skipping = false;
  while (std::getline(in, line)) {
    if (skipping && !line.empty() && line[0] == '|') continue;
    skipping = false;
    out += line + "\n";
    if (line.rfind(marker, 0) != 0) continue;
    std::istringstream words(line.substr(marker.size()));
    std::vector<std::string> groups;
    for (std::string w; words >> w && w != "-->";) groups.push_back(w);
    out += markdown(groups);
    skipping = true;
  }
  if (!text.empty() && text.back() != '\n') out.pop_back();
  return out;
}

}  // namespace isochor
