// Mixing for content hashes and deterministic random numbers.
#pragma once

#include <cstdint>

namespace spall {

/// splitmix64's step and finaliser (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): a strong 64-bit mix, so nearby inputs give unrelated outputs.
inline uint64_t splitmix64(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// A uniform number in [0, 1) from a hash (its top 53 bits).
inline double unitInterval(uint64_t hash) { return double(hash >> 11) * (1.0 / 9007199254740992.0); }

}  // namespace spall
