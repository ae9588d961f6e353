// Parallel loops whose result does not depend on the thread count: each index writes only its
// own slot, and whatever is combined afterwards is combined in index order by the caller.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace spall {

/// Grain for loops whose body does little (a few arithmetic operations per index).
inline constexpr size_t kCheapGrain = 1024;

/// Runs f(k) for k in [0, count) in parallel. Tasks take at least `grain` indices: 1 where f does
/// much (a body, a pair), kCheapGrain where it does little.
template <typename F>
void forEachIndex(size_t count, const F& f, size_t grain = 1)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, grain), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k != range.end(); ++k) f(k);
    });
}

}  // namespace spall
