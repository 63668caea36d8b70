// core/src/config.cpp — reading a case: the JSON text (comments, duplicate keys, depth), the
// --set overrides, the load on rank 0 and its broadcast, and the typed lookups of Config. The
// schema it checks against is in schema.cpp.
#include "coloc/core/config.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <set>

#include "coloc/core/files.hpp"
#include "key_path.hpp"

namespace coloc {
namespace {

/// Thrown by the parser callbacks when a value opens more than kMaxJsonDepth levels of lists and
/// objects; the caller turns it into a ConfigError with the position (tooDeepAt).
struct TooDeep {};

/// The offset in `text` of the '[' or '{' that opens level kMaxJsonDepth + 1 (strings and, when
/// `comments`, // and /* */ comments skipped); npos when there is none. One pass, only after
/// the parser has stopped at that depth.
std::size_t tooDeepAt(const std::string& text, bool comments) {
  int depth = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"') {
      for (++i; i < text.size() && text[i] != '"'; ++i)
        if (text[i] == '\\') ++i;
    } else if (comments && c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      i = text.find('\n', i);
      if (i == std::string::npos) return i;
    } else if (comments && c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      i = text.find("*/", i + 2);
      if (i == std::string::npos) return i;
      ++i;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return std::string::npos;
}

/// "line L, column C (byte offset O)" of offset `at` in `text`.
std::string lineColumn(const std::string& text, std::size_t at) {
  if (at == std::string::npos || at >= text.size()) return "an unknown position";
  const auto line =
      1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  const auto bol = text.rfind('\n', at);
  const std::size_t column = at - (bol == std::string::npos ? 0 : bol + 1) + 1;
  return fmt::format("line {}, column {} (byte offset {})", line, column, at);
}

std::string tooDeepText() {
  return fmt::format("lists and objects nested deeper than {} levels", kMaxJsonDepth);
}

}  // namespace

void applyOverride(Json& doc, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ConfigError("--set", "expected key.path=value, got '" + assignment + "'");
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  Json value;
  try {
    // Bounded nesting (a value of --set is a few levels deep; a deeper one is refused at
    // kMaxJsonDepth, before it is read whole).
    value = Json::parse(text, [](int depth, Json::parse_event_t ev, Json&) {
      using E = Json::parse_event_t;
      if ((ev == E::object_start || ev == E::array_start) && depth >= kMaxJsonDepth)
        throw TooDeep{};
      return true;
    });
  } catch (const TooDeep&) {
    throw ConfigError(path.empty() ? "--set" : path,
                      fmt::format("the --set value has {} (at character {} of the value)",
                                  tooDeepText(), tooDeepAt(text, false) + 1));
  } catch (const Json::exception&) {
    value = text;  // a bare word is a string
  }
  Json* node = &doc;
  const auto parts = detail::splitKey(path);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const auto& p = parts[i];
    if (p.empty()) throw ConfigError(path, "empty segment in --set key path");
    const bool last = i + 1 == parts.size();
    if (node->is_array()) {
      if (!std::all_of(p.begin(), p.end(), ::isdigit))
        throw ConfigError(path, "segment '" + p + "' must index a list");
      // (an index of any length: one that does not fit in 64 bits is out of range too)
      unsigned long long idx = 0;
      const auto [end, ec] = std::from_chars(p.data(), p.data() + p.size(), idx);
      if (ec != std::errc() || end != p.data() + p.size() || idx >= node->size())
        throw ConfigError(path,
                          fmt::format("list index {} is out of range (size {})", p, node->size()));
      node = &(*node)[idx];
    } else {
      if (node->is_null()) *node = Json::object();
      if (!node->is_object()) throw ConfigError(path, "cannot set a key inside a non-object");
      node = &(*node)[p];
    }
    if (last) *node = value;
  }
}

namespace {

/// Refuses a key written twice in one object (JSON would silently keep the last one), naming the
/// key path. Fed the parser's events.
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(std::string source) : source_(std::move(source)) {}
  bool operator()(int, Json::parse_event_t ev, Json& parsed) {
    using E = Json::parse_event_t;
    switch (ev) {
      case E::object_start:
      case E::array_start:
        if (frames_.size() >= static_cast<std::size_t>(kMaxJsonDepth)) throw TooDeep{};
        frames_.push_back(Frame{ev == E::array_start, childPath(), {}, {}, 0});
        break;
      case E::key: {
        Frame& f = frames_.back();
        const std::string k = parsed.get<std::string>();
        if (!f.keys.insert(k).second)
          throw ConfigError(detail::joinKey(f.path, k),
                            "key given twice in the same object of " + source_);
        f.lastKey = k;
        break;
      }
      case E::value:
        if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
        break;
      case E::object_end:
      case E::array_end:
        frames_.pop_back();
        if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array;
    std::string path;
    std::set<std::string> keys;
    std::string lastKey;
    std::size_t index;
  };
  std::string childPath() const {
    if (frames_.empty()) return "";
    const Frame& f = frames_.back();
    return f.array ? fmt::format("{}[{}]", f.path, f.index) : detail::joinKey(f.path, f.lastKey);
  }
  std::string source_;
  std::vector<Frame> frames_;
};

/// "line N (after key "k")" of the first occurrence of `token` in `text` (for the parser's
/// number-overflow error, which gives no position).
std::string whereIs(const std::string& text, const std::string& token) {
  if (token.empty()) return "";
  // the first occurrence outside a // comment, as a whole token
  std::size_t pos = text.find(token);
  for (; pos != std::string::npos; pos = text.find(token, pos + 1)) {
    const auto bol = text.rfind('\n', pos);
    const std::string before =
        text.substr(bol == std::string::npos ? 0 : bol, pos - (bol == std::string::npos ? 0 : bol));
    const char prev = pos > 0 ? text[pos - 1] : ' ';
    if (before.find("//") == std::string::npos && prev != '\'' && prev != '"' &&
        !std::isalnum(static_cast<unsigned char>(prev)))
      break;
  }
  if (pos == std::string::npos) return "";
  const auto line =
      1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(pos), '\n');
  std::string where = fmt::format("line {}", line);
  const auto colon = text.rfind(':', pos);
  if (colon != std::string::npos) {
    const auto q2 = text.rfind('"', colon);
    const auto q1 =
        q2 == std::string::npos || q2 == 0 ? std::string::npos : text.rfind('"', q2 - 1);
    if (q1 != std::string::npos) where += ", key \"" + text.substr(q1 + 1, q2 - q1 - 1) + "\"";
  }
  return where;
}

}  // namespace

Config Config::fromText(const std::string& text, const std::string& source,
                        const std::vector<std::string>& overrides, const Schema& schema) {
  Json doc;
  try {
    doc = Json::parse(text, DuplicateKeyCheck(source), /*allow_exceptions=*/true,
                      /*ignore_comments=*/true);
  } catch (const Json::out_of_range& e) {
    // e.g. 1e400: "number overflow parsing '1e400'"
    std::string what = e.what();
    std::string token;
    const auto q1 = what.find('\'');
    const auto q2 = q1 == std::string::npos ? q1 : what.find('\'', q1 + 1);
    if (q2 != std::string::npos) token = what.substr(q1 + 1, q2 - q1 - 1);
    const std::string where = whereIs(text, token);
    throw ConfigError("", source + ": number " + (token.empty() ? "" : "'" + token + "' ") +
                              "is beyond what a double holds (about 1.8e308)" +
                              (where.empty() ? "" : " at " + where));
  } catch (const TooDeep&) {
    throw ConfigError("", source + ": " + tooDeepText() + " at " +
                              lineColumn(text, tooDeepAt(text, true)) +
                              ": a case file is a few levels deep");
  } catch (const Json::parse_error& e) {
    std::string what = e.what();
    const auto pos = what.find("parse error");
    throw ConfigError(
        "", source + ": malformed JSON: " + (pos == std::string::npos ? what : what.substr(pos)));
  }
  if (!doc.is_object()) throw ConfigError("", source + ": the case must be a JSON object");
  for (const auto& o : overrides) applyOverride(doc, o);
  return Config(schema.resolve(doc), source);
}

Config Config::load(const Comm& comm, const std::string& path,
                    const std::vector<std::string>& overrides, const Schema& schema) {
  std::string text, err;
  if (comm.isRoot()) {
    // A regular file only: stat() before open(), so that a FIFO, a device or a socket is refused
    // by name instead of blocking the run (or reading /dev/zero until the size limit); the
    // descriptor is checked again after the non-blocking open (a file swapped in meanwhile).
    const std::string problem = notRegularFile(path);
    int fd = -1;
    if (problem == "no such file")
      err = "cannot open case file '" + path + "': no such file";
    else if (!problem.empty())
      err = "case file '" + path + "' " + problem;
    else if ((fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)) < 0)
      err = "cannot open case file '" + path + "': " + std::strerror(errno);
    else if (const std::string again = notRegularFile(fd); !again.empty())
      err = "case file '" + path + "' " + again;
    if (err.empty()) {
      // Bounded: a case file is a few kB; a data file given by mistake is refused rather than
      // read until memory runs out.
      std::vector<char> buf(1 << 16);
      while (text.size() <= kMaxCaseFileBytes) {
        const ssize_t n = ::read(fd, buf.data(), buf.size());
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
          err = "cannot read case file '" + path + "': " + std::strerror(errno);
          break;
        }
        if (n == 0) break;
        text.append(buf.data(), static_cast<std::size_t>(n));
      }
      if (err.empty() && text.size() > kMaxCaseFileBytes)
        err = fmt::format("case file '{}' is larger than {} MiB: not a case file", path,
                          kMaxCaseFileBytes >> 20);
      if (!err.empty()) text.clear();
    }
    if (fd >= 0) ::close(fd);
  }
  err = comm.broadcast(err);
  if (!err.empty()) throw ConfigError("", err);
  text = comm.broadcast(text);
  return fromText(text, path, overrides, schema);
}

bool Config::has(const std::string& path) const {
  const Json* node = &json_;
  for (const auto& p : detail::splitKey(path)) {
    if (!node->is_object() || !node->contains(p)) return false;
    node = &(*node)[p];
  }
  return true;
}

const Json& Config::at(const std::string& path) const {
  const Json* node = &json_;
  for (const auto& p : detail::splitKey(path)) {
    if (!node->is_object() || !node->contains(p))
      throw Error("internal: configuration key '" + path + "' was not declared");
    node = &(*node)[p];
  }
  return *node;
}

std::array<double, 3> Config::vec3(const std::string& path) const {
  const auto& v = at(path);
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

std::vector<std::string> Config::names(const std::string& path) const {
  return at(path).get<std::vector<std::string>>();
}

std::array<long long, 3> Config::intVec3(const std::string& path) const {
  const auto& v = at(path);
  return {v[0].get<long long>(), v[1].get<long long>(), v[2].get<long long>()};
}

}  // namespace coloc
