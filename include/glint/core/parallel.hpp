// glint/core/parallel.hpp: work shared among threads by a counter, the one pool the Renderer
// (tiles), the many-light and photon constructions and the VPL method's gather use; and the
// Executor through which a host with a thread pool of its own runs that work instead.
#pragma once

#include <algorithm>
#include <atomic>
#include <functional>
#include <thread>
#include <vector>

namespace glint {

/// A host's executor: runs task(0), ..., task(n - 1), at once on threads of its own or in any
/// order, and returns when all have finished. glint's workers share their work through a
/// counter, so an executor that runs the tasks one after another is correct too (the first
/// task then does all the work). Empty: glint starts std::threads itself.
using Executor = std::function<void(int n, const std::function<void(int)>& task)>;

}  // namespace glint

namespace glint::detail {

/// Runs worker(next) as `threads` workers (0: hardware concurrency, never more than
/// `blocks`); workers take block indices from the shared counter `next` until none of the
/// `blocks` is left. Without an executor the calling thread is one of the workers and the
/// others are std::threads; with one, the executor runs them.
template <class Worker>
void parallel_blocks(int blocks, int threads, const Worker& worker, const Executor& executor = {}) {
    std::atomic<int> next{0};
    int n = threads > 0 ? threads : int(std::thread::hardware_concurrency());
    n = std::clamp(n, 1, std::max(blocks, 1));
    if (executor) {
        executor(n, [&](int) { worker(next); });
        return;
    }
    std::vector<std::thread> pool;
    for (int i = 1; i < n; ++i) pool.emplace_back([&] { worker(next); });
    worker(next);
    for (auto& t : pool) t.join();
}

}  // namespace glint::detail
