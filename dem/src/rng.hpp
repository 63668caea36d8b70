// dem/src/rng.hpp — counter-based random numbers for deterministic particle generation.
//
// Every random quantity of particle `id` is a pure function of (seed, id, stream): a splitmix64
// hash chain (Steele, Lea & Flood 2014, the finaliser of SplittableRandom). No state is carried
// from one particle to the next, so a rank that creates only its own particles draws exactly the
// numbers the serial run draws for them. RandomPermutation is a 4-round Feistel network with
// cycle walking: a bijection of [0, n) that can be inverted, so a rank can ask "which particle
// sits on this lattice site" for the sites of its own block only.
#pragma once

#include <cstdint>

namespace coloc::dem::detail {

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

inline std::uint64_t hash3(std::uint64_t seed, std::uint64_t a, std::uint64_t b) {
  return splitmix64(splitmix64(splitmix64(seed) ^ a) ^ (b * 0xD1B54A32D192ED03ULL));
}

/// Uniform double in [0, 1) from 53 bits of the hash of (seed, id, stream).
inline double uniform01(std::uint64_t seed, std::uint64_t id, std::uint64_t stream) {
  return static_cast<double>(hash3(seed, id, stream) >> 11) * 0x1.0p-53;
}

class RandomPermutation {
 public:
  RandomPermutation(std::uint64_t n, std::uint64_t seed) : n_(n), seed_(seed) {
    int bits = 2;
    while (bits < 62 && (1ULL << bits) < n) bits += 2;
    half_ = bits / 2;
    mask_ = (1ULL << half_) - 1;
  }
  std::uint64_t operator()(std::uint64_t x) const {
    do x = forward(x);
    while (x >= n_);
    return x;
  }
  std::uint64_t inverse(std::uint64_t y) const {
    do y = backward(y);
    while (y >= n_);
    return y;
  }

 private:
  std::uint64_t round(std::uint64_t v, int r) const {
    return hash3(seed_, static_cast<std::uint64_t>(r), v) & mask_;
  }
  std::uint64_t forward(std::uint64_t x) const {
    std::uint64_t l = x >> half_, r = x & mask_;
    for (int k = 0; k < 4; ++k) {
      const std::uint64_t nl = r, nr = l ^ round(r, k);
      l = nl;
      r = nr;
    }
    return (l << half_) | r;
  }
  std::uint64_t backward(std::uint64_t y) const {
    std::uint64_t l = y >> half_, r = y & mask_;
    for (int k = 3; k >= 0; --k) {
      const std::uint64_t pl = r ^ round(l, k), pr = l;
      l = pl;
      r = pr;
    }
    return (l << half_) | r;
  }
  std::uint64_t n_, seed_;
  int half_ = 1;
  std::uint64_t mask_ = 1;
};

}  // namespace coloc::dem::detail
