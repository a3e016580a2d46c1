// glint/core/parallel.hpp: work shared among threads by a counter, the one pool the Renderer
// (tiles) and the VPL method's fixed-point gather (blocks of points) both use.
#pragma once

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace glint::detail {

/// Runs worker(next) on `threads` threads (0: hardware concurrency, never more than
/// `blocks`); workers take block indices from the shared counter `next` until none of the
/// `blocks` is left. The calling thread is one of the workers.
template <class Worker>
void parallel_blocks(int blocks, int threads, const Worker& worker) {
    std::atomic<int> next{0};
    int n = threads > 0 ? threads : int(std::thread::hardware_concurrency());
    n = std::clamp(n, 1, std::max(blocks, 1));
    std::vector<std::thread> pool;
    for (int i = 1; i < n; ++i) pool.emplace_back([&] { worker(next); });
    worker(next);
    for (auto& t : pool) t.join();
}

}  // namespace glint::detail
