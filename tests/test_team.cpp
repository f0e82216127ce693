// kernels/team.hpp: the persistent team that runs the step's parallel
// regions. Every member runs the body once with its own rank; barriers
// order the members' writes; team_for covers every index once; a team of
// another size, a nested call and a call inside an OpenMP region behave as
// the OpenMP regions they replace; the OpenMP fallback gives the same
// results.
#include <gtest/gtest.h>
#include <omp.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <thread>
#include <vector>

#include "kernels/team.hpp"

namespace mmpm {
namespace {

// Restores the thread count and the region kind a test changed.
struct TeamSettings {
  int threads = omp_get_max_threads();
  ~TeamSettings() {
    omp_set_num_threads(threads);
    use_openmp_regions(false);
  }
};

// Each member records its rank and the team size it saw, once per region.
std::vector<int> ranks_seen(int threads, bool parallel, int* size_seen) {
  omp_set_num_threads(threads);
  std::vector<std::atomic<int>> hits(8);
  std::atomic<int> size{-1};
  team_run(parallel, [&] {
    hits[std::size_t(team_rank())].fetch_add(1);
    size.store(team_size());
  });
  *size_seen = size.load();
  std::vector<int> out;
  for (auto& h : hits) out.push_back(h.load());
  return out;
}

TEST(Team, EveryMemberRunsOnceWithItsRank) {
  TeamSettings keep;
  for (int threads : {1, 2, 3, 2, 1, 4}) {  // sizes change between regions
    int size = 0;
    const std::vector<int> hits = ranks_seen(threads, true, &size);
    EXPECT_EQ(size, threads);
    for (int r = 0; r < 8; ++r) EXPECT_EQ(hits[std::size_t(r)], r < threads ? 1 : 0) << r;
  }
}

TEST(Team, NotParallelRunsOnTheCallerAlone) {
  TeamSettings keep;
  int size = 0;
  const std::vector<int> hits = ranks_seen(2, false, &size);
  EXPECT_EQ(size, 1);
  EXPECT_EQ(hits[0], 1);
  EXPECT_EQ(hits[1], 0);
}

TEST(Team, ManyShortRegionsInARowCompleteInOrder) {
  TeamSettings keep;
  omp_set_num_threads(2);
  // Each region adds its index into a slot per member; a region that ran
  // twice, was skipped or overlapped the next would break the sums.
  std::vector<long> sum(2, 0);
  const int regions = 20000;
  for (int i = 0; i < regions; ++i) team_run(true, [&] { sum[std::size_t(team_rank())] += i; });
  const long expected = long(regions) * (regions - 1) / 2;
  EXPECT_EQ(sum[0], expected);
  EXPECT_EQ(sum[1], expected);
}

TEST(Team, BarrierOrdersTheMembersWrites) {
  TeamSettings keep;
  for (int threads : {2, 3}) {
    omp_set_num_threads(threads);
    const int rounds = 2000;
    std::vector<int> slot(std::size_t(threads), -1);
    std::atomic<int> wrong{0};
    team_run(true, [&] {
      const auto me = std::size_t(team_rank()), n = std::size_t(team_size());
      for (int k = 0; k < rounds; ++k) {
        slot[me] = k;  // plain stores: the barrier must publish them
        team_barrier();
        for (std::size_t j = 0; j < n; ++j)
          if (slot[j] != k) wrong.fetch_add(1);
        team_barrier();  // nobody writes round k + 1 before all have read
      }
    });
    EXPECT_EQ(wrong.load(), 0) << threads << " threads";
  }
}

TEST(Team, ForCoversEveryIndexOnceInContiguousBlocks) {
  TeamSettings keep;
  for (int threads : {1, 2, 3}) {
    omp_set_num_threads(threads);
    for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(5), std::size_t(10007)}) {
      std::vector<int> hits(n, 0), owner(n, -1);
      team_for(true, n, [&](std::size_t i) {
        ++hits[i];
        owner[i] = team_rank();
      });
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_EQ(hits[i], 1) << i;
        if (i > 0) {
          ASSERT_LE(owner[i - 1], owner[i]) << "blocks in rank order";
        }
      }
    }
  }
}

TEST(Team, NestedRegionRunsAloneInsideTheMember) {
  TeamSettings keep;
  omp_set_num_threads(2);
  std::atomic<int> inner_size_sum{0}, inner_calls{0}, outer_rank_kept{0};
  team_run(true, [&] {
    const int outer = team_rank();
    team_run(true, [&] {
      inner_size_sum.fetch_add(team_size());
      inner_calls.fetch_add(1);
    });
    if (team_rank() == outer) outer_rank_kept.fetch_add(1);
  });
  EXPECT_EQ(inner_calls.load(), 2);
  EXPECT_EQ(inner_size_sum.load(), 2);  // a team of one each
  EXPECT_EQ(outer_rank_kept.load(), 2);
}

TEST(Team, InsideAnOpenMPRegionFallsBackToOpenMP) {
  TeamSettings keep;
  omp_set_num_threads(2);
  std::atomic<int> ok{0};
#pragma omp parallel num_threads(2)
  {
    // Outside a team: OpenMP's rank and size.
    if (team_rank() == omp_get_thread_num() && team_size() == omp_get_num_threads()) ok++;
    // A region inside runs alone, as a nested OpenMP region would.
    team_run(true, [&] {
      if (team_size() == 1 && team_rank() == 0) ok++;
    });
  }
  EXPECT_EQ(ok.load(), 4);
}

TEST(Team, OpenMPRegionsGiveTheSameRanksAndBarriers) {
  TeamSettings keep;
  use_openmp_regions(true);
  int size = 0;
  const std::vector<int> hits = ranks_seen(2, true, &size);
  EXPECT_EQ(size, 2);
  EXPECT_EQ(hits[0], 1);
  EXPECT_EQ(hits[1], 1);
  std::vector<int> slot(2, -1);
  std::atomic<int> wrong{0};
  team_run(true, [&] {
    for (int k = 0; k < 200; ++k) {
      slot[std::size_t(team_rank())] = k;
      team_barrier();
      if (slot[0] != k || slot[1] != k) wrong++;
      team_barrier();
    }
  });
  EXPECT_EQ(wrong.load(), 0);
}

TEST(Team, AnotherThreadForkingAtTheSameTimeRunsAlone) {
  TeamSettings keep;
  omp_set_num_threads(2);
  // Two callers share one team; whoever finds it busy runs its region on
  // its own thread. Every region still runs every rank of its team once.
  std::atomic<long> work{0};
  auto caller = [&] {
    for (int i = 0; i < 2000; ++i) {
      std::atomic<int> members{0};
      int size = 0;
      team_run(true, [&] {
        members.fetch_add(1);
        if (team_rank() == 0) size = team_size();
      });
      work.fetch_add(members.load() == size ? 1 : 1000000);
    }
  };
  std::thread other(caller);
  caller();
  other.join();
  EXPECT_EQ(work.load(), 4000);
}

TEST(Team, AForkedChildRunsRegionsOnATeamOfItsOwn) {
  TeamSettings keep;
  omp_set_num_threads(2);
  team_run(true, [] {});  // the parent's team exists
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::alarm(20);  // a child waiting on the parent's members would hang: fail instead
    std::atomic<int> members{0};
    for (int i = 0; i < 100; ++i) team_run(true, [&] { members.fetch_add(1); });
    ::_exit(members.load() == 200 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(Team, OfferMinKeepsTheSmallest) {
  TeamSettings keep;
  omp_set_num_threads(2);
  std::atomic<std::size_t> m{SIZE_MAX};
  team_run(true, [&] { offer_min(m, std::size_t(100 + team_rank())); });
  EXPECT_EQ(m.load(), 100u);
  offer_min(m, 7);
  offer_min(m, 9);
  EXPECT_EQ(m.load(), 7u);
}

}  // namespace
}  // namespace mmpm
