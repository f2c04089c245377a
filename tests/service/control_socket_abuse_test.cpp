// The control socket against clients that are not hapticctl: another user, malformed and
// oversized requests, a client that never reads, idle connections holding slots and a hundred
// clients at once. None of them may stall the servo or the other clients.
#include <fcntl.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "daemon.h"
#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

json answer(RawClient& c) { return json::parse(c.line(), nullptr, false); }

// Runs ARGS (args[0] the program) as uid/gid 65534 (nobody) with the supplementary `groups`;
// what it printed and its exit code. A child that cannot become nobody or run the program
// says why on that output and exits 127.
ProcessResult run_as_nobody(const std::vector<std::string>& args, std::vector<gid_t> groups) {
  const std::string err_path = temp_path("nobody" + std::to_string(groups.size()) + ".err");
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);
    dup2(fd, 2);
    dup2(fd, 1);
    if (setgroups(groups.size(), groups.data()) != 0 || setgid(65534) != 0 || setuid(65534) != 0) {
      std::perror("run_as_nobody: cannot become uid/gid 65534");
      _exit(127);
    }
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    std::perror(("run_as_nobody: cannot execute " + args[0] + " as uid 65534").c_str());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ProcessResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_file(err_path);
  return r;
}

TEST(ControlSocketAbuse, APeerOfAnotherUserOutsideTheGroupIsRefusedAndLogged) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to run a client as another user";
  // A directory every user may traverse, and the socket opened to all: so the refusal below
  // is the daemon's own peer-credential check, not the file's mode.
  std::string dir = "/tmp/hapticd-cred-XXXXXX";
  ASSERT_NE(mkdtemp(dir.data()), nullptr);
  ASSERT_EQ(chmod(dir.c_str(), 0755), 0);
  // The client runs from there too: the build tree may lie where nobody cannot reach it (a
  // clone in root's home, mode 0700).
  const std::string ctl = dir + "/hapticctl";
  std::filesystem::copy_file(hapticctl_binary(), ctl);
  std::filesystem::permissions(ctl, std::filesystem::perms(0755));
  Daemon d({"--duration", "120"}, dir);
  ASSERT_TRUE(d.ready());
  ASSERT_EQ(chmod(d.socket().c_str(), 0666), 0);
  const gid_t group = getegid();  // no group hapticd here: the socket has the daemon's group

  const ProcessResult outsider = run_as_nobody({ctl, "--socket", d.socket(), "status"}, {});
  ASSERT_NE(outsider.exit_code, 127) << outsider.err;
  EXPECT_EQ(outsider.exit_code, 1) << outsider.err;
  EXPECT_TRUE(has(outsider.err, "permission denied: not in group")) << outsider.err;
  const ProcessResult member = run_as_nobody({ctl, "--socket", d.socket(), "status"}, {group});
  EXPECT_EQ(member.exit_code, 0) << "a member of the socket's group is served\n" << member.err;
  const ProcessResult stop = run_as_nobody({ctl, "--socket", d.socket(), "stop"}, {});
  EXPECT_EQ(stop.exit_code, 1) << "an outsider cannot stop the servo";
  EXPECT_EQ(d.status()["state"], "running");

  EXPECT_EQ(d.ctl({"stop"}).exit_code, 0);
  const ProcessResult end = d.wait();
  EXPECT_EQ(end.exit_code, 0) << end.err;
  EXPECT_TRUE(has(end.err, "control socket: refused pid")) << end.err;
  EXPECT_TRUE(has(end.err, "uid 65534")) << end.err;
  std::filesystem::remove_all(dir);
}

TEST(ControlSocketAbuse, MalformedRequestsAreAnsweredAndTheConnectionGoesOn) {
  Daemon d({"--duration", "120"});
  ASSERT_TRUE(d.ready());
  RawClient c(d.socket());
  const struct {
    std::string line;
    std::string error;
  } bad[] = {
      {"hello", "not a JSON object"},
      {"[1,2]", "not a JSON object"},
      {R"({"v":2,"cmd":"status"})", "unsupported protocol version"},
      {R"({"cmd":"status"})", "unsupported protocol version"},
      {R"({"v":1,"cmd":"dance","id":42})", "\"cmd\" must be one of"},
      {R"({"v":1,"cmd":"reload","id":"r"})", "reload needs \"config\""},
      {"{\"v\":1,\"cmd\":\"status\",\"id\":\"\xff\xfe\"}", "not a JSON object"},
  };
  for (const auto& b : bad) {
    ASSERT_TRUE(c.send(b.line + "\n"));
    const json a = answer(c);
    EXPECT_EQ(a["ok"], false) << b.line << " -> " << a.dump();
    EXPECT_EQ(a["code"], 2) << a.dump();
    EXPECT_TRUE(has(a.value("error", ""), b.error)) << b.line << " -> " << a.dump();
  }
  ASSERT_TRUE(c.send(R"({"v":1,"cmd":"dance","id":42})"
                     "\n"));
  EXPECT_EQ(answer(c)["id"], 42) << "a readable id is echoed even on an error";
  ASSERT_TRUE(c.send(R"({"v":1,"cmd":"status","id":[7]})"
                     "\n"));
  const json ok = answer(c);
  EXPECT_EQ(ok["ok"], true) << ok.dump();
  EXPECT_EQ(ok["id"], json::array({7}));
  EXPECT_EQ(ok["status"]["state"], "running");
}

TEST(ControlSocketAbuse, AnOversizedRequestIsRefusedAndItsClientDropped) {
  Daemon d({"--duration", "120"});
  ASSERT_TRUE(d.ready());
  RawClient big(d.socket());
  big.send(std::string(300 * 1024, 'x'));  // no newline: a line that never ends
  const json a = answer(big);
  EXPECT_EQ(a["ok"], false);
  EXPECT_TRUE(has(a.value("error", ""), "request longer than 262144 bytes")) << a.dump();
  EXPECT_TRUE(big.closed_by_peer());
  // A client that sends requests and never reads the answers is dropped too.
  RawClient deaf(d.socket());
  const std::string request = R"({"v":1,"cmd":"status"})"
                              "\n";
  std::string burst;
  for (int i = 0; i < 2000; ++i) burst += request;
  bool dropped = false;
  for (int i = 0; i < 200 && !dropped; ++i) dropped = !deaf.send(burst);
  EXPECT_TRUE(dropped) << "the daemon kept answering a client that never reads";
  const json s = d.status();
  EXPECT_EQ(s["state"], "running");
  EXPECT_EQ(s["fault"], nullptr);
}

TEST(ControlSocketAbuse, AHundredClientsAtOnceWhileIdleOnesHoldSlots) {
  Daemon d({"--duration", "120"});
  ASSERT_TRUE(d.ready());
  const std::uint64_t tick_before = d.status()["tick"].get<std::uint64_t>();
  // Ten connections that say nothing, and one that stops mid-line: they hold slots only.
  std::vector<std::unique_ptr<RawClient>> idle;
  for (int i = 0; i < 10; ++i) idle.push_back(std::make_unique<RawClient>(d.socket()));
  idle.back()->send(R"({"v":1,"cmd":"sta)");
  std::vector<std::unique_ptr<RawClient>> clients;
  for (int i = 0; i < 100; ++i) clients.push_back(std::make_unique<RawClient>(d.socket()));
  std::atomic<int> answered{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < 100; ++i) {
    threads.emplace_back([&, i] {
      RawClient& c = *clients[static_cast<std::size_t>(i)];
      if (!c.send(R"({"v":1,"cmd":"status","id":)" + std::to_string(i) + "}\n")) return;
      const json a = json::parse(c.line(), nullptr, false);
      if (a.is_object() && a["ok"] == true && a["id"] == i) ++answered;
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(answered.load(), 100);
  const json s = d.status();
  EXPECT_EQ(s["state"], "running");
  EXPECT_GT(s["tick"].get<std::uint64_t>(), tick_before);
  EXPECT_EQ(d.ctl({"stop"}).exit_code, 0);
  const ProcessResult end = d.wait();
  EXPECT_EQ(end.exit_code, 0) << end.err;
  EXPECT_TRUE(json::parse(read_file(d.summary()))["faults"].empty());
}

}  // namespace
}  // namespace hapticd::testing
