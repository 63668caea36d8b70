// core/src/schema.cpp — the case file's schema (Schema, Range): key kinds, defaults, ranges,
// choices, typed variants and lists; resolve() checks a user document against it and fills the
// defaults, describe() writes the reference (coloc --help-keys). Config (config.cpp) reads with it.
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>

#include "coloc/core/config.hpp"
#include "coloc/core/files.hpp"
#include "key_path.hpp"

namespace coloc {
namespace {

std::string typeName(const Json& v) {
  if (v.is_null()) return "null";
  if (v.is_boolean()) return "a boolean";
  if (v.is_number_integer() || v.is_number_unsigned()) return "an integer";
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_array()) return "a list";
  return "an object";
}

std::string kindName(KeyKind k) {
  switch (k) {
    case KeyKind::Number:
      return "a number";
    case KeyKind::Integer:
      return "an integer";
    case KeyKind::Boolean:
      return "a boolean";
    case KeyKind::String:
      return "a string";
    case KeyKind::Vec3:
      return "a list of 3 numbers";
    case KeyKind::IntVec3:
      return "a list of 3 integers";
    case KeyKind::NumberList:
      return "a list of numbers";
    case KeyKind::NameList:
      return "a list of names";
    case KeyKind::Object:
      return "an object";
    case KeyKind::List:
      return "a list of objects";
  }
  return "?";
}

std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] =
          std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

bool isNumber(const Json& v) {
  return v.is_number() && !v.is_boolean();
}
bool isIntegral(const Json& v) {
  if (v.is_number_integer() || v.is_number_unsigned()) return true;
  if (!v.is_number_float()) return false;
  const double d = v.get<double>();
  return std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9.0e15;
}

/// The value of an integer key, or a ConfigError naming it: never a wrapped value. Integers are
/// 64-bit (signed); a number written with a fraction or exponent is accepted while it is an
/// exact whole number below 2^53. `bits` is 32 for the keys held in an int (list entries).
long long integerOf(const std::string& path, const Json& v, int bits = 64) {
  const long long maxVal = bits == 32 ? 2147483647LL : std::numeric_limits<long long>::max();
  const char* typeText = bits == 32 ? "a 32-bit integer" : "a 64-bit integer";
  auto tooLarge = [&](const std::string& text) {
    return ConfigError(
        path, fmt::format("value {} is beyond what {} holds (at most {})", text, typeText, maxVal));
  };
  if (!isNumber(v) || !isIntegral(v)) {
    if (v.is_number_float()) {
      const double d = v.get<double>();
      if (std::isfinite(d) && d == std::floor(d)) {
        const std::string text = fmt::format("{:g}", d);
        if (std::fabs(d) >= static_cast<double>(maxVal)) throw tooLarge(text);
        throw ConfigError(path, fmt::format("value {} is a whole number too large to be exact as "
                                            "written; write it as a plain integer",
                                            text));
      }
    }
    throw ConfigError(path, "expected an integer, got " + typeName(v));
  }
  long long n = 0;
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(maxVal)) throw tooLarge(fmt::format("{}", u));
    n = static_cast<long long>(u);
  } else if (v.is_number_integer()) {
    n = v.get<long long>();
  } else {
    n = static_cast<long long>(v.get<double>());
  }
  if (n > maxVal || n < -maxVal - 1) throw tooLarge(fmt::format("{}", n));
  return n;
}

void checkRange(const std::string& path, double v, const Range& r) {
  if (!std::isfinite(v)) throw ConfigError(path, "must be finite");
  if (!r.contains(v)) {
    throw ConfigError(path,
                      fmt::format("value {:g} is out of range, expected {}", v, r.describe()));
  }
}

}  // namespace

bool Range::contains(double v) const {
  if (loOpen ? !(v > lo) : !(v >= lo)) return false;
  if (hiOpen ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

std::string Range::describe() const {
  // 15 significant digits: integer bounds such as 2147483647 exactly
  return fmt::format("{}{:.15g}, {:.15g}{}", loOpen ? "(" : "[", lo, hi, hiOpen ? ")" : "]");
}

KeySpec& Schema::insert(const std::string& path, KeySpec spec) {
  const auto dot = path.find('.');
  if (dot != std::string::npos) {
    const std::string head = path.substr(0, dot);
    auto it = std::find_if(keys_.begin(), keys_.end(), [&](auto& kv) { return kv.first == head; });
    if (it == keys_.end()) {
      KeySpec obj;
      obj.kind = KeyKind::Object;
      obj.object = std::make_shared<Schema>();
      obj.defaultValue = Json::object();
      keys_.emplace_back(head, obj);
      it = std::prev(keys_.end());
    }
    if (it->second.kind != KeyKind::Object) throw Error("schema: '" + head + "' is not an object");
    return it->second.object->insert(path.substr(dot + 1), std::move(spec));
  }
  auto it = std::find_if(keys_.begin(), keys_.end(), [&](auto& kv) { return kv.first == path; });
  if (it != keys_.end()) throw Error("schema: key '" + path + "' declared twice");
  keys_.emplace_back(path, std::move(spec));
  return keys_.back().second;
}

Schema& Schema::number(const std::string& path, std::optional<double> def, const std::string& help,
                       Range r) {
  KeySpec s;
  s.kind = KeyKind::Number;
  if (def) s.defaultValue = *def;
  s.range = r;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::optionalNumber(const std::string& path, const std::string& help, Range r) {
  KeySpec s;
  s.kind = KeyKind::Number;
  s.optional = true;
  s.range = r;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::integer(const std::string& path, std::optional<long long> def,
                        const std::string& help, Range r) {
  KeySpec s;
  s.kind = KeyKind::Integer;
  if (def) s.defaultValue = *def;
  s.range = r;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::boolean(const std::string& path, bool def, const std::string& help) {
  KeySpec s;
  s.kind = KeyKind::Boolean;
  s.defaultValue = def;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::string(const std::string& path, std::optional<std::string> def,
                       const std::string& help, std::vector<std::string> choices) {
  KeySpec s;
  s.kind = KeyKind::String;
  if (def) s.defaultValue = *def;
  s.choices = std::move(choices);
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::vec3(const std::string& path, std::optional<std::array<double, 3>> def,
                     const std::string& help, Range r) {
  KeySpec s;
  s.kind = KeyKind::Vec3;
  if (def) s.defaultValue = Json::array({(*def)[0], (*def)[1], (*def)[2]});
  s.range = r;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::intVec3(const std::string& path, std::optional<std::array<long long, 3>> def,
                        const std::string& help, Range r) {
  KeySpec s;
  s.kind = KeyKind::IntVec3;
  if (def) s.defaultValue = Json::array({(*def)[0], (*def)[1], (*def)[2]});
  s.range = r;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::numberList(const std::string& path, std::optional<std::vector<double>> def,
                           const std::string& help, Range r) {
  KeySpec s;
  s.kind = KeyKind::NumberList;
  if (def) s.defaultValue = *def;
  s.range = r;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::nameList(const std::string& path, std::vector<std::string> def,
                         const std::string& help, std::vector<std::string> choices,
                         bool dottedNames, bool unique) {
  KeySpec s;
  s.kind = KeyKind::NameList;
  s.unique = unique;
  s.defaultValue = def;
  s.choices = std::move(choices);
  s.dottedNames = dottedNames;
  s.help = help;
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::variant(const std::string& path, std::map<std::string, Schema> byType,
                        const std::string& defaultType, const std::string& help) {
  KeySpec s;
  s.kind = KeyKind::Object;
  s.help = help;
  for (auto& [name, sch] : byType) s.items[name] = std::make_shared<Schema>(std::move(sch));
  if (!defaultType.empty()) s.defaultValue = Json{{"type", defaultType}};
  insert(path, std::move(s));
  return *this;
}

Schema& Schema::list(const std::string& path, std::map<std::string, Schema> byType,
                     const std::string& help) {
  KeySpec s;
  s.kind = KeyKind::List;
  s.help = help;
  s.defaultValue = Json::array();
  for (auto& [name, sch] : byType) s.items[name] = std::make_shared<Schema>(std::move(sch));
  insert(path, std::move(s));
  return *this;
}

namespace {

Json resolveTyped(const std::map<std::string, std::shared_ptr<Schema>>& byType, const Json& v,
                  const std::string& path) {
  if (!v.is_object()) throw ConfigError(path, "expected an object, got " + typeName(v));
  std::shared_ptr<Schema> sch;
  std::string type;
  if (byType.size() == 1 && byType.count("")) {
    sch = byType.at("");
  } else {
    if (!v.contains("type")) throw ConfigError(path + ".type", "required key is missing");
    if (!v["type"].is_string())
      throw ConfigError(path + ".type", "expected a string, got " + typeName(v["type"]));
    type = v["type"].get<std::string>();
    auto it = byType.find(type);
    if (it == byType.end()) {
      std::string allowed;
      for (auto& kv : byType) allowed += (allowed.empty() ? "" : ", ") + kv.first;
      throw ConfigError(path + ".type", "unknown type '" + type + "', expected one of: " + allowed);
    }
    sch = it->second;
  }
  Json rest = v;
  rest.erase("type");
  Json out = Json::object();
  if (!type.empty()) out["type"] = type;
  const Json resolved = sch->resolve(rest, path);
  for (auto& [k, val] : resolved.items()) out[k] = val;
  return out;
}

}  // namespace

Json Schema::resolve(const Json& user, const std::string& prefix) const {
  if (!user.is_object()) throw ConfigError(prefix, "expected an object, got " + typeName(user));
  for (auto& [k, v] : user.items()) {
    (void)v;
    auto it = std::find_if(keys_.begin(), keys_.end(), [&](auto& kv) { return kv.first == k; });
    if (it == keys_.end()) {
      std::string msg = "unknown key";
      std::string best;
      std::size_t bestD = 3;
      for (auto& kv : keys_) {
        const auto d = editDistance(k, kv.first);
        if (d < bestD) bestD = d, best = kv.first;
      }
      if (!best.empty()) msg += " (did you mean '" + detail::joinKey(prefix, best) + "'?)";
      throw ConfigError(detail::joinKey(prefix, k), msg);
    }
  }
  Json out = Json::object();
  for (const auto& [key, spec] : keys_) {
    const std::string path = detail::joinKey(prefix, key);
    const bool present = user.contains(key);
    if (!present && spec.optional) continue;  // not given: absent from the resolved case too
    if (!present && spec.defaultValue.is_null() && !(spec.kind == KeyKind::Object && spec.object))
      throw ConfigError(path, "required key is missing");
    const Json& v = present ? user.at(key) : spec.defaultValue;
    switch (spec.kind) {
      case KeyKind::Number:
        if (!isNumber(v)) throw ConfigError(path, "expected a number, got " + typeName(v));
        checkRange(path, v.get<double>(), spec.range);
        out[key] = v.get<double>();
        break;
      case KeyKind::Integer: {
        const long long n = integerOf(path, v);
        checkRange(path, static_cast<double>(n), spec.range);
        out[key] = n;
        break;
      }
      case KeyKind::Boolean:
        if (!v.is_boolean()) throw ConfigError(path, "expected a boolean, got " + typeName(v));
        out[key] = v;
        break;
      case KeyKind::String: {
        if (!v.is_string()) throw ConfigError(path, "expected a string, got " + typeName(v));
        const auto s = v.get<std::string>();
        if (!spec.choices.empty() &&
            std::find(spec.choices.begin(), spec.choices.end(), s) == spec.choices.end()) {
          std::string allowed;
          for (auto& c : spec.choices) allowed += (allowed.empty() ? "" : ", ") + c;
          throw ConfigError(path, "invalid value '" + s + "', expected one of: " + allowed);
        }
        out[key] = s;
        break;
      }
      case KeyKind::Vec3:
      case KeyKind::IntVec3:
      case KeyKind::NumberList: {
        if (!v.is_array() || (spec.kind != KeyKind::NumberList && v.size() != 3))
          throw ConfigError(path,
                            fmt::format("expected {}, got {}{}", kindName(spec.kind), typeName(v),
                                        v.is_array() ? fmt::format(" of {}", v.size()) : ""));
        Json arr = Json::array();
        for (std::size_t i = 0; i < v.size(); ++i) {
          const std::string ip = fmt::format("{}[{}]", path, i);
          const bool intOnly = spec.kind == KeyKind::IntVec3;
          if (intOnly) {
            const long long n = integerOf(ip, v[i], 32);
            checkRange(ip, static_cast<double>(n), spec.range);
            arr.push_back(n);
            continue;
          }
          if (!isNumber(v[i])) throw ConfigError(ip, "expected a number, got " + typeName(v[i]));
          checkRange(ip, v[i].get<double>(), spec.range);
          arr.push_back(v[i].get<double>());
        }
        out[key] = arr;
        break;
      }
      case KeyKind::NameList: {
        std::vector<std::string> names;
        if (v.is_string()) {  // "a,b c": names separated by commas or spaces
          std::string cur;
          for (char c : v.get<std::string>() + " ") {
            if (c == ',' || c == ' ' || c == '\t') {
              if (!cur.empty()) names.push_back(cur);
              cur.clear();
            } else {
              cur += c;
            }
          }
        } else if (v.is_array()) {
          for (std::size_t i = 0; i < v.size(); ++i) {
            if (!v[i].is_string())
              throw ConfigError(fmt::format("{}[{}]", path, i),
                                "expected a name (a string), got " + typeName(v[i]));
            names.push_back(v[i].get<std::string>());
          }
        } else {
          throw ConfigError(path,
                            "expected a list of names (or one string of names separated "
                            "by commas), got " +
                                typeName(v));
        }
        std::string allowed;
        for (auto& c : spec.choices) allowed += (allowed.empty() ? "" : ", ") + c;
        if (names.empty()) throw ConfigError(path, "no names given, expected some of: " + allowed);
        for (std::size_t i = 0; i < names.size(); ++i) {
          const auto& n = names[i];
          if (!spec.choices.empty() &&
              std::find(spec.choices.begin(), spec.choices.end(), n) == spec.choices.end() &&
              !(spec.dottedNames && n.find('.') != std::string::npos))
            throw ConfigError(path, "unknown name '" + n + "', expected some of: " + allowed +
                                        (spec.dottedNames ? ", or a key path with a dot" : ""));
          if (spec.unique &&
              std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), n) !=
                  names.begin() + static_cast<std::ptrdiff_t>(i))
            throw ConfigError(path, "'" + n + "' is given twice");
        }
        out[key] = names;
        break;
      }
      case KeyKind::Object:
        if (spec.object) {
          out[key] = spec.object->resolve(present ? v : Json::object(), path);
        } else if (!v.is_null()) {
          out[key] = resolveTyped(spec.items, v, path);
        }
        break;
      case KeyKind::List: {
        if (!v.is_array()) throw ConfigError(path, "expected a list, got " + typeName(v));
        Json arr = Json::array();
        for (std::size_t i = 0; i < v.size(); ++i)
          arr.push_back(resolveTyped(spec.items, v[i], fmt::format("{}[{}]", path, i)));
        out[key] = arr;
        break;
      }
    }
  }
  return out;
}

std::string Schema::describe(const std::string& prefix) const {
  std::ostringstream os;
  for (const auto& [key, spec] : keys_) {
    const std::string path = detail::joinKey(prefix, key);
    if (spec.kind == KeyKind::Object && spec.object) {
      os << spec.object->describe(path);
      continue;
    }
    os << "  " << path << "  (" << kindName(spec.kind);
    if (spec.optional)
      os << ", optional";
    else if (!spec.defaultValue.is_null())
      os << ", default " << spec.defaultValue.dump();
    else
      os << ", required";
    if (spec.kind == KeyKind::Number || spec.kind == KeyKind::Integer || spec.kind == KeyKind::Vec3)
      if (std::isfinite(spec.range.lo) || std::isfinite(spec.range.hi))
        os << ", range " << spec.range.describe();
    if (!spec.choices.empty()) {
      os << (spec.kind == KeyKind::NameList ? ", each one of" : ", one of");
      for (auto& c : spec.choices) os << " " << c;
      if (spec.dottedNames) os << " or a key path with a dot";
    }
    os << ")\n      " << spec.help << "\n";
    for (const auto& [type, sch] : spec.items) {
      const std::string sub = type.empty() ? path + "[]" : path + "{type=" + type + "}";
      os << sch->describe(sub);
    }
  }
  return os.str();
}

}  // namespace coloc
