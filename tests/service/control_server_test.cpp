// The control socket's server in-process, with a handler of the test's own: how it frames
// requests and answers, whatever the daemon behind it does. (The daemon's own answers are
// tested end to end in control_socket_test.cpp.)
#include "service/control/control_server.h"

#include "client/connection.h"
#include "telemetry/state_block.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace hapticd::service {
namespace {

using nlohmann::json;

class ScriptedHandler : public ControlHandler {
 public:
  json handle(const Request& r) override {
    if (r.command == Command::kClearFault) throw ControlRefusal("no fault to clear", 1);
    if (r.command == Command::kReload) throw std::runtime_error("disk on fire");
    return {{"seen", ++seen}, {"client", r.client}};
  }
  void left(std::uint64_t client) override {
    std::lock_guard lock(mutex);
    gone.push_back(client);
  }
  bool holds(std::uint64_t client) const override { return client == held.load(); }
  std::vector<std::uint64_t> left_so_far() {
    std::lock_guard lock(mutex);
    return gone;
  }
  std::mutex mutex;
  std::vector<std::uint64_t> gone;
  std::atomic<std::uint64_t> held{0};
  // "state" passes the test's block, as the daemon passes its own.
  int descriptor(const Request& r) override {
    return r.command == Command::kState && block ? block->fd() : -1;
  }
  int seen = 0;
  telemetry::StateBlock* block = nullptr;
};

// Connects, writes `bytes`, half-closes, and returns every answer line until the server
// hangs up.
std::vector<std::string> converse(const std::string& path, const std::string& bytes) {
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  EXPECT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  EXPECT_EQ(send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL), static_cast<ssize_t>(bytes.size()));
  shutdown(fd, SHUT_WR);
  std::string in;
  char buf[4096];
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 20000) != 1) break;  // a hang: the assertions below say what is missing
    const ssize_t n = recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    in.append(buf, static_cast<std::size_t>(n));
  }
  close(fd);
  std::vector<std::string> lines;
  for (std::size_t at = 0, nl; (nl = in.find('\n', at)) != std::string::npos; at = nl + 1) {
    lines.push_back(in.substr(at, nl - at));
  }
  return lines;
}

struct ServerRig : ::testing::Test {
  ScriptedHandler handler;
  std::string path = ::testing::TempDir() + "control-server-" + std::to_string(getpid()) + ".sock";
  ControlServer server{path, handler};
};

std::string status_line(int id) {
  return R"({"v":1,"cmd":"status","id":)" + std::to_string(id) + "}\n";
}

TEST_F(ServerRig, ManyRequestsInOneWriteThenEndOfInputAreAllAnsweredInOrder) {
  // More lines than the server answers in one turn, all arriving with the end of input: a
  // client that pipelines its requests and half-closes must get every answer.
  std::string requests;
  for (int i = 1; i <= 40; ++i) requests += status_line(i);
  const std::vector<std::string> answers = converse(path, requests);
  ASSERT_EQ(answers.size(), 40u);
  for (int i = 1; i <= 40; ++i) {
    const json a = json::parse(answers[i - 1]);
    EXPECT_EQ(a["id"], i);
    EXPECT_EQ(a["ok"], true);
    EXPECT_EQ(a["seen"], i);
  }
}

TEST_F(ServerRig, ClientsThatLeaveWithoutTheirAnswersDoNotHoldTheSlots) {
  // More clients than the server has slots each send requests and close at once: their
  // answers cannot be delivered. Kept until they went idle, they would lock every other
  // client (the operator's `stop` among them) out for a minute.
  std::string requests;
  for (int i = 1; i <= 20; ++i) requests += status_line(i);
  for (int i = 0; i < 2 * ControlServer::kMaxClients; ++i) {
    const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    ASSERT_EQ(send(fd, requests.data(), requests.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(requests.size()));
    close(fd);
  }
  const auto start = std::chrono::steady_clock::now();
  const std::vector<std::string> answers = converse(path, status_line(99));
  ASSERT_EQ(answers.size(), 1u) << "a client after them was not answered";
  EXPECT_EQ(json::parse(answers[0])["id"], 99);
  // A deadline for a lock-out (a minute), not a timing: the answer takes milliseconds.
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(15));
}

TEST_F(ServerRig, ASecondServerOnALiveSocketIsRefusedAndTheFirstServesOn) {
  ScriptedHandler other;
  try {
    ControlServer second(path, other);
    ADD_FAILURE() << "a second server took over a live daemon's socket";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another process is serving this socket"),
              std::string::npos)
        << e.what();
  }
  const std::vector<std::string> answers = converse(path, status_line(5));
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_EQ(handler.seen, 1);
}

TEST(ControlServer, AStaleSocketFileOfAnEarlierRunIsReplaced) {
  const std::string path = ::testing::TempDir() + "stale-" + std::to_string(getpid()) + ".sock";
  ScriptedHandler handler;
  // A crashed daemon leaves its socket file behind: make one by hand.
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  close(fd);
  ControlServer again(path, handler);
  EXPECT_EQ(converse(path, status_line(1)).size(), 1u);
}

TEST_F(ServerRig, AnUnfinishedLastLineAtEndOfInputIsNotAnswered) {
  const std::vector<std::string> answers =
      converse(path, status_line(1) + R"({"v":1,"cmd":"status","id":2})");
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_EQ(json::parse(answers[0])["id"], 1);
  EXPECT_EQ(handler.seen, 1) << "the unfinished request must not be carried out";
}

TEST_F(ServerRig, ARefusalKeepsItsCodeAndAnyOtherExceptionIsCodeOne) {
  const std::vector<std::string> answers =
      converse(path, R"({"v":1,"cmd":"clear-fault","id":"c"})"
                     "\n"
                     R"({"v":1,"cmd":"reload","id":"r","config":""})"
                     "\n"
                     "garbage\n");
  ASSERT_EQ(answers.size(), 3u);
  const json refused = json::parse(answers[0]), failed = json::parse(answers[1]),
             malformed = json::parse(answers[2]);
  EXPECT_EQ(refused["ok"], false);
  EXPECT_EQ(refused["error"], "no fault to clear");
  EXPECT_EQ(refused["code"], 1);
  EXPECT_EQ(failed["error"], "disk on fire");
  EXPECT_EQ(failed["code"], 1);
  EXPECT_EQ(failed["id"], "r");
  EXPECT_EQ(malformed["code"], 2);
  EXPECT_TRUE(malformed["id"].is_null());
}

// Each connection is a client of its own number; when it ends, the handler hears which. One the
// handler says holds something is never evicted for a newcomer, however idle.
TEST_F(ServerRig, AClientThatLeavesIsNamedAndOneHoldingSomethingIsNeverEvicted) {
  client::Connection keeper(path, 5000);
  const auto kept = keeper.call({{"cmd", "status"}})["client"].get<std::uint64_t>();
  handler.held = kept;
  std::uint64_t first_gone = 0;
  {
    client::Connection passer(path, 5000);
    first_gone = passer.call({{"cmd", "status"}})["client"].get<std::uint64_t>();
    EXPECT_NE(first_gone, kept);
  }
  const auto left_includes = [&](std::uint64_t id) {
    const std::vector<std::uint64_t> g = handler.left_so_far();
    return std::find(g.begin(), g.end(), id) != g.end();
  };
  for (int i = 0; i < 200 && !left_includes(first_gone); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(left_includes(first_gone));
  // Every other slot taken by idle clients, idle past the eviction age: a newcomer evicts one
  // of them, never the keeper.
  std::vector<std::unique_ptr<client::Connection>> idle;
  for (int i = 0; i < ControlServer::kMaxClients - 1; ++i) {
    idle.push_back(std::make_unique<client::Connection>(path, 5000));
    idle.back()->call({{"cmd", "status"}});
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(ControlServer::kEvictAfterMs + 200));
  client::Connection newcomer(path, 5000);
  EXPECT_EQ(newcomer.call({{"cmd", "status"}})["ok"], true);
  EXPECT_FALSE(left_includes(kept));
  EXPECT_EQ(keeper.call({{"cmd", "status"}})["client"], kept);
}

// A descriptor goes with its own answer's first byte, between answers that carry none: the
// client library maps the block it passed and reads what was published into it.
TEST_F(ServerRig, TheStateBlockIsPassedWithItsAnswerAndMapsForReading) {
  telemetry::StateBlock block(16, 1000000, 3, 3);
  handler.block = &block;
  client::StateSample s;
  s.tick = 7;
  s.x[2] = 0.11;
  block.publish(s);
  client::Connection c(path, 5000);
  EXPECT_EQ(c.status()["state"], nullptr);  // the scripted status: {"seen": 1, "client": 1}
  client::StateReader reader = c.state();
  EXPECT_EQ(c.call({{"cmd", "status"}})["seen"], 3);  // the answer after it is whole too
  client::StateSample read;
  ASSERT_TRUE(reader.latest(read));
  EXPECT_EQ(read.tick, 7u);
  EXPECT_EQ(read.x[2], 0.11);
  handler.block = nullptr;  // no descriptor passed: the client says so
  try {
    c.state();
    FAIL() << "a state answer without a descriptor was taken";
  } catch (const client::ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("carried no descriptor"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hapticd::service
