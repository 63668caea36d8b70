// dem/src/rows.cpp — generic pack/unpack of particle rows over the field table.
#include "rows.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <type_traits>

#include "buffers.hpp"
#include "coloc/core/error.hpp"

namespace coloc::dem::detail {

namespace {

/// The columns of one operation, grouped by kind (positions, other doubles, int64, int): a row
/// holds them in that order. Built per call on the stack from the table (no allocation), so the
/// row loops below run over plain pointer arrays.
template <bool Const>
struct Plan {
  template <class T>
  using Ptr = std::conditional_t<Const, const T*, T*>;
  static constexpr int kMax = 64;
  std::array<Ptr<double>, kMax> pos{}, dbl{};
  std::array<Ptr<std::int64_t>, kMax> i64{};
  std::array<Ptr<int>, kMax> i32{};
  int np = 0, nd = 0, nl = 0, ni = 0;
  // columns outside the operation (zeroed in fresh rows)
  std::array<Ptr<double>, kMax> zd{};
  std::array<Ptr<std::int64_t>, kMax> zl{};
  std::array<Ptr<int>, kMax> zi{};
  int nzd = 0, nzl = 0, nzi = 0;
  std::size_t width() const { return static_cast<std::size_t>(np + nd + nl + ni); }

  template <class Store>
  Plan(Store& p, unsigned op) {
    forEachField(p, [&](const FieldInfo& fi, auto* cols) {
      using T = typename std::remove_cvref_t<decltype(cols[0])>::value_type;
      const bool in = (fi.ops & op) != 0;
      for (int k = 0; k < fi.components; ++k) {
        auto* c = cols[k].data();
        if (np + nd + nl + ni >= kMax || nzd + nzl + nzi >= kMax)
          throw Error("more than 64 particle field columns");
        if constexpr (std::is_same_v<T, double>) {
          if (!in)
            zd[static_cast<std::size_t>(nzd++)] = c;
          else if (fi.ops & kOpPosition)
            pos[static_cast<std::size_t>(np++)] = c;
          else
            dbl[static_cast<std::size_t>(nd++)] = c;
        } else if constexpr (std::is_same_v<T, std::int64_t>) {
          if (in)
            i64[static_cast<std::size_t>(nl++)] = c;
          else
            zl[static_cast<std::size_t>(nzl++)] = c;
        } else {
          if (in)
            i32[static_cast<std::size_t>(ni++)] = c;
          else
            zi[static_cast<std::size_t>(nzi++)] = c;
        }
      }
    });
  }

  void pack(std::size_t i, const double* shift, double* out) const requires Const {
    if (shift)
      for (int j = 0; j < np; ++j) *out++ = pos[static_cast<std::size_t>(j)][i] + shift[j];
    else
      for (int j = 0; j < np; ++j) *out++ = pos[static_cast<std::size_t>(j)][i];
    for (int j = 0; j < nd; ++j) *out++ = dbl[static_cast<std::size_t>(j)][i];
    for (int j = 0; j < nl; ++j) *out++ = static_cast<double>(i64[static_cast<std::size_t>(j)][i]);
    for (int j = 0; j < ni; ++j) *out++ = static_cast<double>(i32[static_cast<std::size_t>(j)][i]);
  }

  void unpack(const double* in, std::size_t i, bool fresh) const requires(!Const) {
    for (int j = 0; j < np; ++j) pos[static_cast<std::size_t>(j)][i] = *in++;
    for (int j = 0; j < nd; ++j) dbl[static_cast<std::size_t>(j)][i] = *in++;
    for (int j = 0; j < nl; ++j)
      i64[static_cast<std::size_t>(j)][i] = static_cast<std::int64_t>(*in++);
    for (int j = 0; j < ni; ++j) i32[static_cast<std::size_t>(j)][i] = static_cast<int>(*in++);
    if (!fresh) return;
    for (int j = 0; j < nzd; ++j) zd[static_cast<std::size_t>(j)][i] = 0;
    for (int j = 0; j < nzl; ++j) zl[static_cast<std::size_t>(j)][i] = 0;
    for (int j = 0; j < nzi; ++j) zi[static_cast<std::size_t>(j)][i] = 0;
  }
};

}  // namespace

void packRow(const ParticleStore& p, unsigned op, std::size_t i, const double* shift, double* out) {
  Plan<true>(p, op).pack(i, shift, out);
}

void packRows(const ParticleStore& p, unsigned op, std::span<const int> idx, const double* shift,
              double* out) {
  const Plan<true> plan(p, op);
  const std::size_t w = plan.width();
  for (const int i : idx) {
    plan.pack(static_cast<std::size_t>(i), shift, out);
    out += w;
  }
}

void unpackRow(ParticleStore& p, unsigned op, const double* in, std::size_t i, bool fresh) {
  Plan<false>(p, op).unpack(in, i, fresh);
}

void unpackRows(ParticleStore& p, unsigned op, const double* in, std::size_t m, std::size_t first,
                bool fresh) {
  const Plan<false> plan(p, op);
  const std::size_t w = plan.width();
  for (std::size_t q = 0; q < m; ++q, in += w) plan.unpack(in, first + q, fresh);
}

void resizeAll(ParticleStore& p, std::size_t n) {
  forEachColumn(p, [n](auto& c) { ensure(c, n); });
  forEachColumn(p, [n](auto& c) { c.resize(n); });
}

void copyRow(ParticleStore& p, std::size_t from, std::size_t to) {
  forEachColumn(p, [=](auto& c) { c[to] = c[from]; });
}

std::size_t columnBytes(const ParticleStore& p) {
  std::size_t b = 0;
  forEachField(p, [&](const FieldInfo& fi, const auto* cols) {
    for (int k = 0; k < fi.components; ++k) b += cap(cols[k]);
  });
  return b;
}

}  // namespace coloc::dem::detail

namespace coloc::dem {

std::size_t ParticleStore::addField(const std::string& name, int components, unsigned ops) {
  if (components != 1 && components != 3)
    throw Error(fmt::format("particle field '{}': 1 or 3 components, not {}", name, components));
  bool taken = false;
  forEachField(*this, [&](const FieldInfo& fi, const auto*) { taken = taken || fi.name == name; });
  if (taken) throw Error("particle field '" + name + "' is already declared");
  if (name.empty() || name.find_first_of(" \t\n;/") != std::string::npos)
    throw Error("particle field '" + name + "': a name without blanks, ';' or '/' is needed");
  // a field refreshed on ghosts is also copied to them when they are made
  if (ops & kOpGhostUpdate) ops |= kOpGhostBuild;
  ExtraField e;
  e.name = name;
  e.components = components;
  e.ops = ops & ~static_cast<unsigned>(kOpPosition);
  e.data.assign(static_cast<std::size_t>(components), std::vector<double>(size(), 0.0));
  extra.push_back(std::move(e));
  return extra.size() - 1;
}

namespace {
template <class S>
auto& extraColumn(S& s, std::string_view name, int component) {
  for (auto& e : s.extra)
    if (e.name == name && component >= 0 && component < e.components)
      return e.data[static_cast<std::size_t>(component)];
  throw Error(fmt::format("no particle field '{}' with component {}", name, component));
}
}  // namespace

std::vector<double>& ParticleStore::field(std::string_view name, int component) {
  return extraColumn(*this, name, component);
}
const std::vector<double>& ParticleStore::field(std::string_view name, int component) const {
  return extraColumn(*this, name, component);
}

std::size_t rowWidth(const ParticleStore& p, unsigned op) {
  std::size_t w = 0;
  forEachField(p, [&](const FieldInfo& fi, const auto*) {
    if (fi.ops & op) w += static_cast<std::size_t>(fi.components);
  });
  return w;
}

ParticleStore ownedRows(const ParticleStore& p) {
  ParticleStore q;
  for (const auto& e : p.extra)
    if (e.ops & kOpState) q.addField(e.name, e.components, e.ops);
  const std::size_t n = p.nOwned;
  q.nOwned = n;
  // the two tables list the state fields in the same order (q's extras are p's state extras)
  std::vector<const void*> from;
  forEachField(p, [&](const FieldInfo& fi, const auto* cols) {
    if (fi.ops & kOpState)
      for (int k = 0; k < fi.components; ++k) from.push_back(&cols[k]);
  });
  std::size_t c = 0;
  forEachField(q, [&](const FieldInfo& fi, auto* cols) {
    using V = std::remove_reference_t<decltype(cols[0])>;
    if (!(fi.ops & kOpState)) return;
    for (int k = 0; k < fi.components; ++k) {
      const auto& src = *static_cast<const V*>(from[c++]);
      cols[k].assign(src.begin(), src.begin() + static_cast<std::ptrdiff_t>(n));
    }
  });
  return q;
}

}  // namespace coloc::dem
