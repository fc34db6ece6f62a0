#include "rgbl/core/task_pool.hpp"

#include <catch2/catch.hpp>

#include <atomic>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

TEST_CASE("task pool: parallel_for runs every index exactly once, for any thread count", "[core][pool]") {
  for (const int threads : {1, 2, 3, 8}) {
    rgbl::TaskPool pool(threads);
    CHECK(pool.threads() == threads);
    for (const std::size_t n : {0UL, 1UL, 2UL, 7UL, 100UL}) {
      std::vector<std::atomic<int>> runs(n);
      pool.parallel_for(n, [&](std::size_t i) { runs[i].fetch_add(1); });
      for (std::size_t i = 0; i < n; ++i) CHECK(runs[i].load() == 1);
    }
  }
  CHECK(rgbl::TaskPool().threads() == rgbl::TaskPool::hardware_threads());
}

TEST_CASE("task pool: the work really spreads over the threads", "[core][pool]") {
  rgbl::TaskPool pool(2);
  // two indices that each wait for the other to have started: only finishes when both run at once
  std::atomic<int> started{0};
  pool.parallel_for(2, [&](std::size_t) {
    started.fetch_add(1);
    while (started.load() < 2) std::this_thread::yield();
  });
  CHECK(started.load() == 2);
}

TEST_CASE("task pool: exceptions reach the caller, the lowest index's first", "[core][pool]") {
  rgbl::TaskPool pool(3);
  std::atomic<int> ran{0};
  CHECK_THROWS_WITH(pool.parallel_for(10,
                                      [&](std::size_t i) {
                                        ran.fetch_add(1);
                                        if (i == 4 || i == 7) throw std::runtime_error("index " + std::to_string(i));
                                      }),
                    "index 4");
  CHECK(ran.load() == 10);  // the others still ran: nothing is left referring to the caller's frame
  rgbl::TaskPool::Task task = pool.submit([] { throw std::invalid_argument("from a task"); });
  CHECK_THROWS_AS(task.wait(), std::invalid_argument);
  CHECK_FALSE(task.valid());
  task.wait();  // a waited task is empty: no-op
}

TEST_CASE("task pool: nested parallelism and waiting inside a task do not deadlock", "[core][pool]") {
  for (const int threads : {1, 2, 4}) {
    rgbl::TaskPool pool(threads);
    std::vector<int> sums(6, 0);
    std::vector<rgbl::TaskPool::Task> outer;
    for (std::size_t t = 0; t < sums.size(); ++t) {
      outer.push_back(pool.submit([&pool, &sums, t] {
        std::vector<int> parts(5, 0);
        pool.parallel_for(parts.size(), [&](std::size_t i) { parts[i] = static_cast<int>(t * 10 + i); });
        for (const int p : parts) sums[t] += p;
      }));
    }
    for (auto& task : outer) task.wait();
    for (std::size_t t = 0; t < sums.size(); ++t) CHECK(sums[t] == static_cast<int>(50 * t + 10));
  }
}

TEST_CASE("task pool: a task destroyed unwaited is waited for, a one-thread pool runs tasks when waited", "[core][pool]") {
  rgbl::TaskPool single(1);
  int value = 0;
  {
    rgbl::TaskPool::Task task = single.submit([&] { value = 7; });
    CHECK(value == 0);  // no worker: nothing runs before someone waits
  }
  CHECK(value == 7);  // the destructor waited (its captures may be on the caller's stack)

  rgbl::TaskPool pool(2);
  std::atomic<bool> done{false};
  {
    rgbl::TaskPool::Task task = pool.submit([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      done = true;
    });
  }
  CHECK(done.load());
}
