// glint/core/buckets.hpp: items listed per bucket and stored flat (a counting sort): bucket
// b's items are items[start[b]] .. items[start[b + 1] - 1], in the order they were listed.
// The uniform grid's cells, the photon gather's hash grid and the surface groups' triangle
// lists are built this way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace glint {

/// Fills `start` (buckets + 1 offsets) and `items` from the listings that `for_each` makes:
/// for_each(emit) calls emit(item, bucket) for every listing (bucket < buckets), the same
/// listings in the same order each time, since it is called twice: to count, then to fill.
template <class ForEach>
void fill_buckets(std::size_t buckets, ForEach&& for_each, std::vector<std::uint32_t>& start,
                  std::vector<std::uint32_t>& items) {
    start.assign(buckets + 1, 0);
    for_each([&](std::size_t, std::size_t bucket) { ++start[bucket + 1]; });
    for (std::size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
    items.resize(start.back());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for_each([&](std::size_t item, std::size_t bucket) { items[fill[bucket]++] = std::uint32_t(item); });
}

}  // namespace glint
