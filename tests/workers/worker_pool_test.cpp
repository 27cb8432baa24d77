// The core's worker processes and wire format (core/workers): a frame
// crosses whole whatever its size, a worker's death is its channel's end
// with the wait status, a dead worker can be started again, and a child
// dies with its parent.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <manibench/wire_format.hpp>
#include <manibench/worker_pool.hpp>
#include <thread>

namespace manibench {
namespace {

TEST(WireFormat, FieldsRoundTripAndATruncatedPayloadThrows) {
  wire::Writer w;
  const std::vector<double> numbers = {1.5, -2, 1e300};
  w.fields(uint8_t(7), std::string("name"), numbers, std::vector<std::string>{"a", "bc"});
  w.array<double>(nullptr, 0);
  std::string framed, payload;
  {
    int fds[2];
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
    ASSERT_TRUE(wire::sendFrame(fds[0], w));
    close(fds[0]);
    ASSERT_TRUE(wire::receiveFrame(fds[1], payload));
    EXPECT_FALSE(wire::receiveFrame(fds[1], framed));  // end of stream
    close(fds[1]);
  }
  wire::Reader r(payload);
  uint8_t kind = 0;
  std::string name;
  std::vector<double> back;
  std::vector<std::string> words;
  r.fields(kind, name, back, words);
  EXPECT_EQ(kind, 7);
  EXPECT_EQ(name, "name");
  EXPECT_EQ(back, numbers);
  EXPECT_EQ(words, (std::vector<std::string>{"a", "bc"}));
  EXPECT_EQ(r.arrayCount<double>(), 0u);
  const std::string cut = w.data().substr(0, 10);
  wire::Reader short_reader(cut);
  EXPECT_THROW(short_reader.fields(kind, name, back), std::runtime_error);
}

TEST(WireFormat, TakeFrameWaitsForAWholeFrame) {
  wire::Writer w;
  w.str(std::string(100000, 'x'));
  std::string bytes = std::string(4, '\0') + w.data();
  const uint32_t size = uint32_t(w.data().size());
  std::memcpy(bytes.data(), &size, 4);
  std::string buffer = bytes.substr(0, 5000), payload;
  EXPECT_FALSE(wire::takeFrame(buffer, payload));
  buffer += bytes.substr(5000);
  ASSERT_TRUE(wire::takeFrame(buffer, payload));
  EXPECT_EQ(payload, w.data());
  EXPECT_TRUE(buffer.empty());
}

std::string readText(const std::string& payload) {
  wire::Reader r(payload);
  return r.str();
}

wire::Writer makeText(const std::string& text) {
  wire::Writer w;
  w.str(text);
  return w;
}

// Polls until `done` or ten seconds have passed.
void pollUntil(WorkerPool& pool, const std::function<bool()>& done,
               const std::function<void(std::size_t, const std::string&)>& on_frame,
               const WorkerPool::EndHandler& on_end) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done() && std::chrono::steady_clock::now() < end) pool.poll(100, on_frame, on_end);
}

// Workers echo each text doubled; worker 1 aborts on "die". The pool
// reports the end with the wait status; the worker is started again and
// answers.
TEST(WorkerPool, EchoesReportsADeathAndStartsAgain) {
  WorkerPool pool(2, [](std::size_t index, int fd) {
    std::string payload;
    while (wire::receiveFrame(fd, payload)) {
      const std::string text = readText(payload);
      if (text == "die" && index == 1) abort();
      wire::sendFrame(fd, makeText(text + text));
    }
    return 3;
  });
  pool.start(0);
  pool.start(1);
  std::vector<std::string> got(2);
  std::vector<int> ends(2, -1);
  const auto on_frame = [&](std::size_t i, const std::string& payload) { got[i] = readText(payload); };
  const auto on_end = [&](std::size_t i, int status) { ends[i] = status; };
  ASSERT_TRUE(pool.send(0, makeText("ab")));
  ASSERT_TRUE(pool.send(1, makeText(std::string(300000, 'z'))));  // more than a socket buffer
  pollUntil(pool, [&] { return !got[0].empty() && !got[1].empty(); }, on_frame, on_end);
  EXPECT_EQ(got[0], "abab");
  EXPECT_EQ(got[1], std::string(600000, 'z'));

  pool.send(1, makeText("die"));
  pollUntil(pool, [&] { return ends[1] != -1; }, on_frame, on_end);
  ASSERT_TRUE(WIFSIGNALED(ends[1])) << describeExit(ends[1]);
  EXPECT_EQ(WTERMSIG(ends[1]), SIGABRT);
  EXPECT_FALSE(pool.isRunning(1));
  EXPECT_TRUE(pool.isRunning(0));

  pool.start(1);
  got[1].clear();
  ASSERT_TRUE(pool.send(1, makeText("again")));
  pollUntil(pool, [&] { return !got[1].empty(); }, on_frame, on_end);
  EXPECT_EQ(got[1], "againagain");
  // Stopping closes the channel: the body returns, its value the status.
  const int status = pool.stop(0, false);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
}

// The zygote forks workers on request, also after one died, and reaps
// them for the parent: a killed one's status is its signal. Its workers
// leave when their channel closes.
TEST(Zygote, StartsWorkersReapsAndReplacesADeadOne) {
  Zygote zygote([](std::size_t index, int fd) {
    std::string payload;
    while (wire::receiveFrame(fd, payload))
      wire::sendFrame(fd, makeText(readText(payload) + "!" + std::to_string(index)));
    return 4;
  });
  Child first = zygote.spawn(7);
  ASSERT_GT(first.pid, 0) << first.error;
  std::string payload;
  ASSERT_TRUE(wire::sendFrame(first.fd, makeText("hi")));
  ASSERT_TRUE(wire::receiveFrame(first.fd, payload));
  EXPECT_EQ(readText(payload), "hi!7");
  kill(first.pid, SIGKILL);
  EXPECT_FALSE(wire::receiveFrame(first.fd, payload));  // its end of stream
  close(first.fd);
  const int killed = zygote.reap(first.pid);
  ASSERT_TRUE(WIFSIGNALED(killed)) << describeExit(killed);
  EXPECT_EQ(WTERMSIG(killed), SIGKILL);
  const Child second = zygote.spawn(1);
  ASSERT_GT(second.pid, 0) << second.error;
  EXPECT_NE(second.pid, first.pid);
  ASSERT_TRUE(wire::sendFrame(second.fd, makeText("again")));
  ASSERT_TRUE(wire::receiveFrame(second.fd, payload));
  EXPECT_EQ(readText(payload), "again!1");
  close(second.fd);
  const int left = zygote.reap(second.pid);
  ASSERT_TRUE(WIFEXITED(left)) << describeExit(left);
  EXPECT_EQ(WEXITSTATUS(left), 4);
}

// A pool whose workers a zygote forks: the same event loop, the same wait
// statuses, and receive() for a user that waits on one worker.
TEST(WorkerPool, ThroughAZygoteReportsASignal) {
  WorkerPool pool(
      2,
      [](std::size_t, int fd) {
        std::string payload;
        while (wire::receiveFrame(fd, payload)) {
          if (readText(payload) == "hang") pause();
          wire::sendFrame(fd, makeText(readText(payload) + "?"));
        }
        return 0;
      },
      {}, Launch::kZygote);
  pool.start(0);
  pool.start(1);
  std::string payload;
  ASSERT_TRUE(pool.send(0, makeText("a")));
  ASSERT_EQ(pool.receive(0, payload, std::chrono::steady_clock::time_point::max()), wire::Received::kFrame);
  EXPECT_EQ(readText(payload), "a?");
  // One that does not answer: timed out, then killed and reaped.
  ASSERT_TRUE(pool.send(1, makeText("hang")));
  ASSERT_EQ(pool.receive(1, payload, std::chrono::steady_clock::now() + std::chrono::milliseconds(200)),
            wire::Received::kTimedOut);
  const int hung = pool.stop(1, true);
  ASSERT_TRUE(WIFSIGNALED(hung)) << describeExit(hung);
  EXPECT_EQ(WTERMSIG(hung), SIGKILL);
  // One killed from outside: poll hands its end over with the signal.
  const pid_t victim = pool.getPid(0);
  kill(victim, SIGABRT);  // the zygote's workers ignore SIGTERM, as it does
  int status = -2;
  pollUntil(pool, [&] { return status != -2; }, [](std::size_t, const std::string&) {},
            [&](std::size_t, int s) { status = s; });
  ASSERT_TRUE(WIFSIGNALED(status)) << describeExit(status);
  EXPECT_EQ(WTERMSIG(status), SIGABRT);
  EXPECT_NE(describeExit(status).find("SIGABRT"), std::string::npos);
}

// PR_SET_PDEATHSIG: a child's child dies with the child that started it.
TEST(WorkerPool, AChildDiesWithItsParent) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const Child middle = spawnChild({}, [&](int) {
    ChildOptions options;
    options.channel = false;
    const Child grandchild = spawnChild(options, [](int) {
      for (;;) pause();
      return 0;
    });
    (void)!write(fds[1], &grandchild.pid, sizeof grandchild.pid);
    return 0;  // leaves at once: the grandchild is killed
  });
  ASSERT_GT(middle.pid, 0);
  pid_t grandchild = -1;
  ASSERT_EQ(read(fds[0], &grandchild, sizeof grandchild), ssize_t(sizeof grandchild));
  int status = 0;
  waitpid(middle.pid, &status, 0);
  close(middle.fd);
  bool gone = false;
  for (int i = 0; i < 500 && !gone; ++i) {
    // Reparented to init (or a subreaper), so not ours to reap: gone or a zombie.
    gone = kill(grandchild, 0) != 0;
    if (!gone) {
      char state = 0;
      FILE* stat = std::fopen(("/proc/" + std::to_string(grandchild) + "/stat").c_str(), "r");
      if (stat) {
        (void)!std::fscanf(stat, "%*d %*s %c", &state);
        std::fclose(stat);
      }
      gone = state == 'Z' || state == 'X';
    }
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(gone) << "process " << grandchild << " outlived its parent";
  close(fds[0]);
  close(fds[1]);
}

}  // namespace
}  // namespace manibench
