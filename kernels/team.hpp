// Fork-join for the step's parallel regions on a persistent team whose
// members wait by spinning on one cache line, instead of an OpenMP
// `parallel` region.
//
// Why: a step has ~34 regions (one per color of each colored pass, one per
// node pass). libgomp wakes its team and joins it through futex system
// calls even when its threads are spinning (300 000 futex calls in the
// 4795 steps of inputs/two_layer.toml), and on this virtual machine a
// system call costs ~1.2 us: an empty region took 3.2 us on two threads
// (1.3 on one) and a barrier 1.5 us. Here a fork is one store the waiting
// member sees, a join one counter, a barrier a counter and a phase: 0.75 us
// per empty region, 0.24 us per barrier on two threads, no system call
// while the members spin (docs/performance.md "Parallel regions without
// system calls").
//
// team_run(parallel, body) runs body() on every member of a team of
// omp_get_max_threads() threads (the calling thread is member 0), or on the
// calling thread alone when `parallel` is false, when that is 1, or when it
// is called inside a team or an OpenMP parallel region already (as a nested
// OpenMP region would). Inside, team_rank() / team_size() give the member
// and the team's size, team_barrier() waits for every member. Outside a
// team they fall back to OpenMP's, so a kernel written for a team also runs
// orphaned inside a test's `#pragma omp parallel`. The work's split depends
// only on (rank, size), as with OpenMP, so results do not change.
#pragma once

#include <omp.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <memory>
#include <mutex>
#include <string_view>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif
#include <pthread.h>

namespace mmpm {

namespace team_detail {

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#endif
}

// Pauses before a waiting member yields its core (a barrier or a join: the
// others are working, so the wait is short unless the machine has fewer
// cores than the team), and before an idle member sleeps between regions.
inline constexpr int kSpinBeforeYield = 1 << 12;
inline constexpr int kSpinBeforeSleep = 1 << 15;

// Spins until pred() holds; yields the core after kSpinBeforeYield pauses.
template <class Pred>
inline void wait_until(Pred&& pred) {
  for (int i = 0; !pred(); ++i) {
    if (i < kSpinBeforeYield)
      cpu_relax();
    else
      std::this_thread::yield();
  }
}

struct Team {
  int size = 1;
  // The barrier: members arrived in this phase, and the phase.
  alignas(64) std::atomic<int> arrived{0};
  alignas(64) std::atomic<std::uint32_t> phase{0};

  void barrier() {
    if (size == 1) return;
    const std::uint32_t ph = phase.load(std::memory_order_relaxed);
    if (arrived.fetch_add(1, std::memory_order_acq_rel) == size - 1) {
      arrived.store(0, std::memory_order_relaxed);
      phase.store(ph + 1, std::memory_order_release);
    } else {
      wait_until([&] { return phase.load(std::memory_order_acquire) != ph; });
    }
  }
};

struct Membership {
  Team* team = nullptr;
  int rank = 0;
};
inline thread_local Membership tl_member;

// The persistent members 1..size-1 of the one team, started on the first
// fork of a team of that size and replaced when the size changes.
class Pool {
 public:
  // Runs body(ctx) on `size` members, the caller as member 0.
  void run(int size, void (*body)(void*), void* ctx) {
    if (size != team_.size) resize(size);
    body_ = body;
    ctx_ = ctx;
    remaining_.store(size - 1, std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_seq_cst);  // publishes body_, ctx_, remaining_
    if (sleepers_.load(std::memory_order_seq_cst) > 0) generation_.notify_all();
    member(0, body, ctx);
    wait_until([&] { return remaining_.load(std::memory_order_acquire) == 0; });
  }

  std::mutex& lock() { return lock_; }

 private:
  void member(int rank, void (*body)(void*), void* ctx) {
    const Membership saved = tl_member;
    tl_member = {&team_, rank};
    body(ctx);
    tl_member = saved;
  }

  void worker(int rank, std::uint64_t seen) {
    for (;;) {
      std::uint64_t g;
      for (int i = 0; (g = generation_.load(std::memory_order_acquire)) == seen; ++i) {
        if (i < kSpinBeforeSleep) {
          cpu_relax();
          continue;
        }
        // Idle longer than a step's serial gaps (output, setup): sleep
        // until the next fork. The fork reads sleepers_ after publishing
        // the generation, and this re-reads the generation after counting
        // itself (both sequentially consistent), so one of the two sees
        // the other.
        sleepers_.fetch_add(1, std::memory_order_seq_cst);
        if (generation_.load(std::memory_order_seq_cst) == seen) generation_.wait(seen);
        sleepers_.fetch_sub(1, std::memory_order_seq_cst);
        i = 0;
      }
      seen = g;
      if (stopping_.load(std::memory_order_acquire)) return;
      member(rank, body_, ctx_);
      remaining_.fetch_sub(1, std::memory_order_release);
    }
  }

  void resize(int size) {
    stop_workers();
    team_.size = size;
    team_.arrived.store(0, std::memory_order_relaxed);
    stopping_.store(false, std::memory_order_relaxed);
    // A new member starts from the generation before its first fork, which
    // may be published before the thread first looks.
    const std::uint64_t now = generation_.load(std::memory_order_relaxed);
    for (int r = 1; r < size; ++r) workers_.emplace_back([this, r, now] { worker(r, now); });
  }

  void stop_workers() {
    if (workers_.empty()) return;
    stopping_.store(true, std::memory_order_release);
    generation_.fetch_add(1, std::memory_order_seq_cst);
    generation_.notify_all();
    for (std::thread& t : workers_) t.join();
    workers_.clear();
    team_.size = 1;
  }

  Team team_;
  std::vector<std::thread> workers_;
  // The fork's line: a waiting member that sees the generation change finds
  // the body in the same line.
  alignas(64) std::atomic<std::uint64_t> generation_{0};
  void (*body_)(void*) = nullptr;
  void* ctx_ = nullptr;
  alignas(64) std::atomic<int> remaining_{0};
  alignas(64) std::atomic<int> sleepers_{0};
  std::atomic<bool> stopping_{false};
  std::mutex lock_;  // one fork at a time; another caller runs alone
};

// The process's pool. Never destroyed: its members end with the process
// (as OpenMP's do), so no exit path waits on them. A child of fork() has
// only the forking thread, so it starts a pool of its own (leaving the
// parent's copy, whose threads it does not have).
inline Pool*& pool_pointer() {
  static Pool* p = [] {
    pthread_atfork(nullptr, nullptr, [] { pool_pointer() = new Pool; });
    return new Pool;
  }();
  return p;
}
inline Pool& pool() {
  return *pool_pointer();
}

// Regions as OpenMP `parallel` regions instead: use_openmp_regions, or
// the environment variable MMPM_REGIONS=openmp at start-up (the escape
// hatch, and the baseline of the whole-run comparison in
// docs/performance.md).
inline bool openmp_regions_from_environment() {
  const char* v = std::getenv("MMPM_REGIONS");
  return v && std::string_view(v) == "openmp";
}
inline std::atomic<bool> openmp_regions{openmp_regions_from_environment()};

}  // namespace team_detail

// The calling member's rank and the team's size (OpenMP's outside a team).
inline int team_rank() {
  const team_detail::Membership& m = team_detail::tl_member;
  return m.team ? m.rank : omp_get_thread_num();
}
inline int team_size() {
  const team_detail::Membership& m = team_detail::tl_member;
  return m.team ? m.team->size : omp_get_num_threads();
}

// Every member waits for the others (OpenMP's barrier outside a team).
inline void team_barrier() {
  if (team_detail::Team* t = team_detail::tl_member.team) {
    t->barrier();
    return;
  }
#pragma omp barrier
}

// The regions that follow run as OpenMP `parallel` regions (true) or on the
// persistent team (false, the default): bench/bench_team.cpp measures one
// against the other in the same run. Not while a region runs.
inline void use_openmp_regions(bool on) {
  team_detail::openmp_regions.store(on, std::memory_order_relaxed);
}

// body() on every member of the team (see the top of this file). A body
// must not throw: an exception in a member ends the program, as one leaving
// an OpenMP region does.
template <class Body>
void team_run(bool parallel, Body&& body) {
  using team_detail::Membership;
  using team_detail::tl_member;
  using B = std::remove_reference_t<Body>;
  auto call = [](void* ctx) noexcept { (*static_cast<B*>(ctx))(); };
  void* const ctx = const_cast<void*>(static_cast<const void*>(std::addressof(body)));
  if (team_detail::openmp_regions.load(std::memory_order_relaxed) && !tl_member.team) {
    // team_rank() and friends fall back to OpenMP's inside.
#pragma omp parallel if (parallel)
    call(ctx);
    return;
  }
  const int size = parallel ? omp_get_max_threads() : 1;
  if (size > 1 && !tl_member.team && !omp_in_parallel()) {
    team_detail::Pool& pool = team_detail::pool();
    std::unique_lock<std::mutex> own(pool.lock(), std::try_to_lock);
    if (own.owns_lock()) {
      pool.run(size, call, ctx);
      return;
    }
  }
  // Alone: a team of one, as a nested or `if (false)` OpenMP region.
  team_detail::Team solo;
  const Membership saved = tl_member;
  tl_member = {&solo, 0};
  call(ctx);
  tl_member = saved;
}

// The calling thread's contiguous block [first, last) of n items, the
// block a schedule(static) loop would give it up to rounding: passes that
// cut their work this way (and TileSchedule's colored passes, which follow
// the particle order) keep each particle on one thread from pass to pass.
inline std::pair<std::size_t, std::size_t> thread_block(std::size_t n, std::size_t threads,
                                                        std::size_t i) {
  return {n * i / threads, n * (i + 1) / threads};
}

// body(i) for i in [0, n), each member on its thread_block.
template <class Body>
void team_for(bool parallel, std::size_t n, Body&& body) {
  team_run(parallel, [&] {
    const auto [first, last] = thread_block(n, std::size_t(team_size()), std::size_t(team_rank()));
    for (std::size_t i = first; i < last; ++i) body(i);
  });
}

// Thread-safe running minimum, for a team's min-reductions: each member
// offers its own minimum once, before the join.
inline void offer_min(std::atomic<std::size_t>& m, std::size_t v) {
  std::size_t cur = m.load(std::memory_order_relaxed);
  while (v < cur && !m.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}

}  // namespace mmpm
