// Case-file parsing, overrides and strict validation.
#include <gtest/gtest.h>

#include "coloc/core/config.hpp"

using coloc::Config;
using coloc::ConfigError;
using coloc::Range;
using coloc::Schema;

namespace {

Schema schema() {
  Schema s;
  s.number("fluid.nu", 1e-6, "kinematic viscosity", Range::positive());
  s.integer("run.steps", 10, "steps", Range::nonNegative());
  s.boolean("run.verbose", false, "chatty");
  s.string("run.mode", "coupled", "mode", {"coupled", "fluid"});
  s.vec3("domain.length", std::nullopt, "box", Range::positive());
  s.list("particles.sources",
         {{"lattice", Schema().intVec3("count", std::nullopt, "n", Range::atLeast(1))},
          {"list", Schema().numberList("x", std::nullopt, "positions")}},
         "particle sources");
  return s;
}

std::string errorOf(const std::string& text, std::vector<std::string> overrides = {}) {
  try {
    Config::fromText(text, "case.json", overrides, schema());
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Config, DefaultsCommentsAndTypes) {
  const auto cfg = Config::fromText(R"(// a comment
    { /* block */ "domain": { "length": [1, 2, 3] } })",
                                    "c", {}, schema());
  EXPECT_DOUBLE_EQ(cfg.number("fluid.nu"), 1e-6);
  EXPECT_EQ(cfg.integer("run.steps"), 10);
  EXPECT_EQ(cfg.string("run.mode"), "coupled");
  EXPECT_EQ(cfg.vec3("domain.length")[2], 3.0);
  EXPECT_TRUE(cfg.at("particles.sources").is_array());
}

TEST(Config, OverridesApplyBeforeValidation) {
  const auto cfg = Config::fromText(
      R"({ "domain": { "length": [1, 2, 3] } })", "c",
      {"run.steps=42", "run.mode=fluid", "domain.length=[4,5,6]", "fluid.nu=2.5e-5"}, schema());
  EXPECT_EQ(cfg.integer("run.steps"), 42);
  EXPECT_EQ(cfg.string("run.mode"), "fluid");
  EXPECT_EQ(cfg.vec3("domain.length")[0], 4.0);
  EXPECT_DOUBLE_EQ(cfg.number("fluid.nu"), 2.5e-5);
}

TEST(Config, OverrideIntoListItem) {
  const auto cfg = Config::fromText(
      R"({ "domain": { "length": [1, 1, 1] },
           "particles": { "sources": [ { "type": "lattice", "count": [1, 1, 1] } ] } })",
      "c", {"particles.sources.0.count=[2,3,4]"}, schema());
  EXPECT_EQ(cfg.at("particles.sources")[0]["count"][1].get<int>(), 3);
}

TEST(Config, ErrorsNameTheKeyPath) {
  const std::string base = R"("domain": { "length": [1, 1, 1] })";
  EXPECT_EQ(errorOf("{" + base + ", \"fluid\": { \"nuu\": 1 } }"),
            "fluid.nuu: unknown key (did you mean 'fluid.nu'?)");
  EXPECT_EQ(errorOf("{" + base + ", \"fluid\": { \"nu\": \"x\" } }"),
            "fluid.nu: expected a number, got a string");
  EXPECT_EQ(errorOf("{" + base + ", \"fluid\": { \"nu\": 0 } }"),
            "fluid.nu: value 0 is out of range, expected (0, inf]");
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"steps\": 1.5 } }"),
            "run.steps: expected an integer, got a number");
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"verbose\": 1 } }"),
            "run.verbose: expected a boolean, got an integer");
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"mode\": \"x\" } }"),
            "run.mode: invalid value 'x', expected one of: coupled, fluid");
  EXPECT_EQ(errorOf("{}"), "domain.length: required key is missing");
  EXPECT_EQ(errorOf(R"({ "domain": { "length": [1, -1, 1] } })"),
            "domain.length[1]: value -1 is out of range, expected (0, inf]");
  EXPECT_EQ(errorOf("{" + base + R"(, "particles": { "sources": [ { "type": "blob" } ] } })"),
            "particles.sources[0].type: unknown type 'blob', expected one of: lattice, list");
  EXPECT_EQ(errorOf("{" + base + R"(, "particles": { "sources": [ { "type": "lattice" } ] } })"),
            "particles.sources[0].count: required key is missing");
  EXPECT_EQ(errorOf("{" + base + R"(, "particles": { "sources": [ { "count": [1,1,1] } ] } })"),
            "particles.sources[0].type: required key is missing");
  EXPECT_NE(errorOf("{ oops }").find("malformed JSON"), std::string::npos);
  EXPECT_EQ(errorOf("{" + base + "}", {"run.steps"}),
            "--set: expected key.path=value, got 'run.steps'");
  EXPECT_EQ(errorOf("{" + base + "}", {"run.stepz=4"}),
            "run.stepz: unknown key (did you mean 'run.steps'?)");
}

TEST(Config, DescribeListsEveryKey) {
  const auto text = schema().describe();
  for (const char* k : {"fluid.nu", "run.steps", "run.mode", "domain.length", "particles.sources"})
    EXPECT_NE(text.find(k), std::string::npos) << k;
}

TEST(Config, NumbersPastTheirTypeDuplicatesAndOverflow) {
  const std::string base = R"("domain": { "length": [1, 1, 1] })";
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"steps\": 9223372036854775808 } }"),
            "run.steps: value 9223372036854775808 is beyond what a 64-bit integer holds (at most "
            "9223372036854775807)");
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"steps\": 18446744073709551615 } }"),
            "run.steps: value 18446744073709551615 is beyond what a 64-bit integer holds (at most "
            "9223372036854775807)");
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"steps\": 1e20 } }"),
            "run.steps: value 1e+20 is beyond what a 64-bit integer holds (at most "
            "9223372036854775807)");
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"steps\": 9223372036854775807 } }"), "");
  EXPECT_EQ(errorOf("{" + base + ", \"run\": { \"steps\": 2e3 } }"), "");
  EXPECT_EQ(errorOf("{" + base + R"(, "particles": { "sources": [ { "type": "lattice",
            "count": [1, 2147483648, 1] } ] } })"),
            "particles.sources[0].count[1]: value 2147483648 is beyond what a 32-bit integer holds "
            "(at most 2147483647)");
  EXPECT_EQ(errorOf("{" + base + ", \"fluid\": { \"nu\": 1, \"nu\": 2 } }"),
            "fluid.nu: key given twice in the same object of case.json");
  EXPECT_EQ(errorOf("{" + base + R"(, "particles": { "sources": [ { "type": "list", "x": [1] },
            { "type": "list", "x": [1], "x": [2] } ] } })"),
            "particles.sources[1].x: key given twice in the same object of case.json");
  EXPECT_EQ(errorOf("// 1e400 in a comment\n{" + base + ",\n \"fluid\": { \"nu\": 1e400 } }"),
            "case.json: number '1e400' is beyond what a double holds (about 1.8e308) at line 3, "
            "key \"nu\"");
  EXPECT_EQ(errorOf("{" + base + "}", {"fluid.nu=1e400"}),
            "fluid.nu: expected a number, got a string");
}

TEST(Config, NameLists) {
  Schema s;
  s.nameList("run.columns", {"a", "b"}, "columns", {"a", "b", "c"});
  auto names = [&](const std::string& text, std::vector<std::string> over = {}) {
    return Config::fromText(text, "case.json", over, s).names("run.columns");
  };
  auto error = [&](const std::string& text, std::vector<std::string> over = {}) {
    try {
      Config::fromText(text, "case.json", over, s);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(names("{}"), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(names(R"({ "run": { "columns": ["c", "a", "c"] } })"),
            (std::vector<std::string>{"c", "a", "c"}));
  // --set: a JSON list, or one string of names separated by commas and spaces
  EXPECT_EQ(names("{}", {"run.columns=c, b"}), (std::vector<std::string>{"c", "b"}));
  EXPECT_EQ(names("{}", {R"(run.columns=["b"])"}), (std::vector<std::string>{"b"}));
  EXPECT_EQ(error("{}", {"run.columns=a,x"}),
            "run.columns: unknown name 'x', expected some of: a, b, c");
  EXPECT_EQ(error(R"({ "run": { "columns": [] } })"),
            "run.columns: no names given, expected some of: a, b, c");
  EXPECT_EQ(error(R"({ "run": { "columns": ["a", 1] } })"),
            "run.columns[1]: expected a name (a string), got an integer");
  EXPECT_EQ(error(R"({ "run": { "columns": 1 } })"),
            "run.columns: expected a list of names (or one string of names separated by commas), "
            "got an integer");
  EXPECT_NE(s.describe().find("each one of a b c"), std::string::npos);
}

// Optional keys (issue 50): no default and no sentinel; absent from the resolved case when not
// given, range-checked when given. A unique name list refuses a name given twice.
TEST(Config, OptionalKeysHaveNoSentinel) {
  Schema s;
  s.optionalNumber("wall.temperature", "K", Range::between(0.0, 1e6));
  s.number("wall.other", 1.0, "x");
  s.nameList("run.columns", {"a"}, "columns", {"a", "b"}, /*dottedNames=*/false, /*unique=*/true);
  const auto absent = Config::fromText("{}", "case.json", {}, s);
  EXPECT_FALSE(absent.has("wall.temperature"));
  EXPECT_FALSE(absent.optionalNumber("wall.temperature").has_value());
  EXPECT_FALSE(absent.json()["wall"].contains("temperature"));  // not shown in a report either
  const auto given = Config::fromText(R"({ "wall": { "temperature": 350 } })", "case.json", {}, s);
  EXPECT_EQ(given.optionalNumber("wall.temperature").value(), 350.0);
  auto error = [&](const std::vector<std::string>& over) {
    try {
      Config::fromText("{}", "case.json", over, s);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error({"wall.temperature=-7"}),
            "wall.temperature: value -7 is out of range, expected [0, 1000000]");
  EXPECT_EQ(error({"run.columns=a,b,a"}), "run.columns: 'a' is given twice");
  EXPECT_NE(s.describe().find("wall.temperature  (a number, optional"), std::string::npos);
  // a --set list index of any length: out of range, never an exception of the parser
  EXPECT_EQ(errorOf(R"({ "domain": { "length": [1, 1, 1] }, "particles": { "sources": [] } })",
                    {"particles.sources.99999999999999999999.count=1"}),
            "particles.sources.99999999999999999999.count: list index 99999999999999999999 is "
            "out of range (size 0)");
}
