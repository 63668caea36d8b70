// dem/src/rows.cpp — generic pack/unpack of particle rows over the field table.
#include "rows.hpp"

#include <algorithm>

#include "buffers.hpp"
#include "coloc/core/error.hpp"

namespace coloc::dem::detail {

std::size_t rowWidth(const ParticleStore& p, unsigned op) {
  std::size_t w = 0;
  forEachField(p, [&](const FieldInfo& fi, const auto*) {
    if (fi.ops & op) w += static_cast<std::size_t>(fi.components);
  });
  return w;
}

void packRow(const ParticleStore& p, unsigned op, std::size_t i, const double* shift, double* out) {
  forEachField(p, [&](const FieldInfo& fi, const auto* cols) {
    if (!(fi.ops & op)) return;
    const bool pos = shift && (fi.ops & kOpPosition);
    for (int k = 0; k < fi.components; ++k) {
      const double v = static_cast<double>(cols[k][i]);
      *out++ = pos ? v + shift[k] : v;
    }
  });
}

// The batch versions go column by column over blocks of kBlock rows: the block's rows stay in
// L1 while every column is written into them (whole sends are larger than L2).
constexpr std::size_t kBlock = 256;

void packRows(const ParticleStore& p, unsigned op, std::span<const int> idx, const double* shift,
              double* out) {
  const std::size_t w = rowWidth(p, op), m = idx.size();
  for (std::size_t q0 = 0; q0 < m; q0 += kBlock) {
    const std::size_t qn = std::min(kBlock, m - q0);
    const int* ix = idx.data() + q0;
    std::size_t o = 0;
    forEachField(p, [&](const FieldInfo& fi, const auto* cols) {
      if (!(fi.ops & op)) return;
      const bool pos = shift && (fi.ops & kOpPosition);
      for (int k = 0; k < fi.components; ++k, ++o) {
        const auto* c = cols[k].data();
        double* r = out + q0 * w + o;
        const double s = pos ? shift[k] : 0.0;
        if (pos) {
          for (std::size_t q = 0; q < qn; ++q, r += w)
            *r = static_cast<double>(c[static_cast<std::size_t>(ix[q])]) + s;
        } else {
          for (std::size_t q = 0; q < qn; ++q, r += w)
            *r = static_cast<double>(c[static_cast<std::size_t>(ix[q])]);
        }
      }
    });
  }
}

void unpackRow(ParticleStore& p, unsigned op, const double* in, std::size_t i, bool fresh) {
  forEachField(p, [&](const FieldInfo& fi, auto* cols) {
    using T = typename std::remove_reference_t<decltype(cols[0])>::value_type;
    if (fi.ops & op) {
      for (int k = 0; k < fi.components; ++k) cols[k][i] = static_cast<T>(*in++);
    } else if (fresh) {
      for (int k = 0; k < fi.components; ++k) cols[k][i] = T{};
    }
  });
}

void unpackRows(ParticleStore& p, unsigned op, const double* in, std::size_t m, std::size_t first,
                bool fresh) {
  const std::size_t w = rowWidth(p, op);
  for (std::size_t q0 = 0; q0 < m; q0 += kBlock) {
    const std::size_t qn = std::min(kBlock, m - q0);
    std::size_t o = 0;
    forEachField(p, [&](const FieldInfo& fi, auto* cols) {
      using T = typename std::remove_reference_t<decltype(cols[0])>::value_type;
      if (fi.ops & op) {
        for (int k = 0; k < fi.components; ++k, ++o) {
          T* c = cols[k].data() + first + q0;
          const double* r = in + q0 * w + o;
          for (std::size_t q = 0; q < qn; ++q, r += w) c[q] = static_cast<T>(*r);
        }
      } else if (fresh) {
        for (int k = 0; k < fi.components; ++k) std::fill_n(cols[k].data() + first + q0, qn, T{});
      }
    });
  }
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
    throw Error("particle field '" + name + "': 1 or 3 components, not " +
                std::to_string(components));
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
  throw Error("no particle field '" + std::string(name) + "' with component " +
              std::to_string(component));
}
}  // namespace

std::vector<double>& ParticleStore::field(std::string_view name, int component) {
  return extraColumn(*this, name, component);
}
const std::vector<double>& ParticleStore::field(std::string_view name, int component) const {
  return extraColumn(*this, name, component);
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
