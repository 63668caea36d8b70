// coloc/core/config.hpp — case files: JSON with comments, `--set key.path=value` overrides,
// strict validation against a schema that each folder declares for its own keys.
//
// Usage (the driver):
//   Schema s;  fv::declareConfig(s);  dem::declareConfig(s); ...
//   Config cfg = Config::load(comm, "case.json", {"fluid.nu=1e-5"}, s);
//   double nu = cfg.number("fluid.nu");
// The case text is read on rank 0 and broadcast, so every rank validates the same text and
// reaches the same verdict: an error is thrown on every rank, with the key path in the message.
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "coloc/core/comm.hpp"
#include "coloc/core/error.hpp"

namespace coloc {

using Json = nlohmann::ordered_json;

/// Numeric bound of a key: [lo, hi] with each side open or closed.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool loOpen = false, hiOpen = false;
  static Range any() { return {}; }
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range nonNegative() {
    return {0.0, std::numeric_limits<double>::infinity(), false, false};
  }
  static Range atLeast(double v) {
    return {v, std::numeric_limits<double>::infinity(), false, false};
  }
  static Range between(double a, double b) { return {a, b, false, false}; }
  static Range openClosed(double a, double b) { return {a, b, true, false}; }
  bool contains(double v) const;
  std::string describe() const;
};

enum class KeyKind {
  Number,
  Integer,
  Boolean,
  String,
  Vec3,
  IntVec3,
  NumberList,
  NameList,
  Object,
  List
};

class Schema;

/// A key of the schema. Object keys hold child schemas; List keys hold item schemas chosen by the
/// item's "type" field (or a single item schema under the name "").
struct KeySpec {
  KeyKind kind = KeyKind::Number;
  Json defaultValue;                 // null: required (unless optional)
  bool optional = false;             // absent: left out of the resolved case (no default)
  bool unique = false;               // NameList: each name at most once
  Range range;                       // numbers, integers, and each component of vectors
  std::vector<std::string> choices;  // strings: allowed values (empty: any)
  bool dottedNames = false;          // NameList: names with a '.' pass too (the caller checks them)
  std::string help;
  std::shared_ptr<Schema> object;                        // Object
  std::map<std::string, std::shared_ptr<Schema>> items;  // List (by "type", or "" for any)
};

class Schema {
 public:
  Schema& number(const std::string& path, std::optional<double> def, const std::string& help,
                 Range r = Range::any());
  /// A number that may be left out, with no default standing in for it: absent, the key is
  /// missing from the resolved case too (Config::optionalNumber gives std::nullopt), so that no
  /// sentinel value (-1, 0) can be mistaken for a given one; given, it is checked like any number.
  Schema& optionalNumber(const std::string& path, const std::string& help, Range r = Range::any());
  Schema& integer(const std::string& path, std::optional<long long> def, const std::string& help,
                  Range r = Range::any());
  Schema& boolean(const std::string& path, bool def, const std::string& help);
  Schema& string(const std::string& path, std::optional<std::string> def, const std::string& help,
                 std::vector<std::string> choices = {});
  Schema& vec3(const std::string& path, std::optional<std::array<double, 3>> def,
               const std::string& help, Range r = Range::any());
  Schema& intVec3(const std::string& path, std::optional<std::array<long long, 3>> def,
                  const std::string& help, Range r = Range::any());
  Schema& numberList(const std::string& path, std::optional<std::vector<double>> def,
                     const std::string& help, Range r = Range::any());
  /// A non-empty list of names, each one of `choices`: a JSON list of strings, or one string of
  /// names separated by commas or spaces (`--set run.progress_columns=step,time`). Resolved to
  /// the list. With `dottedNames`, a name holding a '.' passes too (a key path the caller
  /// checks, e.g. a report.json key as a progress column). `unique`: a name given twice is
  /// refused (a list of columns, each shown once).
  Schema& nameList(const std::string& path, std::vector<std::string> def, const std::string& help,
                   std::vector<std::string> choices, bool dottedNames = false, bool unique = false);
  /// An optional object whose keys depend on its "type" (e.g. a boundary condition).
  Schema& variant(const std::string& path, std::map<std::string, Schema> byType,
                  const std::string& defaultType, const std::string& help);
  /// A list of objects, each validated by the schema named by its "type".
  Schema& list(const std::string& path, std::map<std::string, Schema> byType,
               const std::string& help);

  /// Validate `user` (unknown keys, types, ranges, choices) and fill defaults. Throws
  /// ConfigError naming the key path. `prefix` is the path of this schema in the document.
  Json resolve(const Json& user, const std::string& prefix = "") const;

  /// One line per key: path, kind, default, range, help (for `coloc --help-keys`).
  std::string describe(const std::string& prefix = "") const;

 private:
  KeySpec& insert(const std::string& path, KeySpec spec);
  std::vector<std::pair<std::string, KeySpec>> keys_;  // declaration order
  friend class Config;
};

/// Case files larger than this are refused unread (a case file is a few kB).
inline constexpr std::size_t kMaxCaseFileBytes = std::size_t{64} << 20;
/// Lists and objects nested deeper than this in a case file or a --set value are refused (with
/// the file and line, or the key), as soon as the parser reaches that depth.
inline constexpr int kMaxJsonDepth = 64;

/// A validated, resolved case. Accessors take a dotted path into the resolved JSON.
class Config {
 public:
  Config() = default;
  Config(Json resolved, std::string source)
      : json_(std::move(resolved)), source_(std::move(source)) {}

  /// Read `path` on rank 0, broadcast, strip comments, apply `overrides` (each "a.b.c=value",
  /// value parsed as JSON, else taken as a string), validate. Throws ConfigError on every rank.
  static Config load(const Comm& comm, const std::string& path,
                     const std::vector<std::string>& overrides, const Schema& schema);
  /// Same from text already in memory (tests, restarts).
  static Config fromText(const std::string& text, const std::string& source,
                         const std::vector<std::string>& overrides, const Schema& schema);

  const Json& json() const { return json_; }
  const std::string& source() const { return source_; }
  bool has(const std::string& path) const;
  const Json& at(const std::string& path) const;
  double number(const std::string& path) const { return at(path).get<double>(); }
  /// A key declared with Schema::optionalNumber: its value, or std::nullopt when not given.
  std::optional<double> optionalNumber(const std::string& path) const {
    if (!has(path)) return std::nullopt;
    return at(path).get<double>();
  }
  long long integer(const std::string& path) const { return at(path).get<long long>(); }
  bool boolean(const std::string& path) const { return at(path).get<bool>(); }
  std::string string(const std::string& path) const { return at(path).get<std::string>(); }
  std::array<double, 3> vec3(const std::string& path) const;
  std::array<long long, 3> intVec3(const std::string& path) const;
  std::vector<std::string> names(const std::string& path) const;

 private:
  Json json_;
  std::string source_;
};

/// Apply one "a.b.c=value" override to a document (creates missing objects; numeric segments
/// index lists). Throws ConfigError for a malformed override.
void applyOverride(Json& doc, const std::string& assignment);

}  // namespace coloc
