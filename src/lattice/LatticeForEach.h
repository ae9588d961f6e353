// Lattice::forEach, for the lattice's passes (one .cpp each): a loop over particles or bonds, in
// parallel for large lattices and in order for small ones.
#pragma once

#include <spall/core/Parallel.h>
#include <spall/lattice/Lattice.h>

namespace spall {

/// Below this many particles a lattice steps on one thread: dispatching a parallel loop costs
/// more than its work (the 1 296-particle cantilever test took 8.5 s in parallel).
constexpr size_t kParallelParticles = 2048;

template <typename F>
void Lattice::forEach(size_t count, const F& f) const
{
    forEach(count, f, kCheapGrain);
}

template <typename F>
void Lattice::forEach(size_t count, const F& f, size_t grain) const
{
    if (particleCount() >= kParallelParticles) {
        forEachIndex(count, f, grain);
        return;
    }
    for (size_t i = 0; i < count; ++i) f(i);
}

}  // namespace spall
