#include "process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace hapticd::testing {
namespace {

pid_t spawn(const std::vector<std::string>& args, const std::vector<std::string>& env, int& out_fd,
            int& err_fd, int stdout_fd = -1) {
  int out[2], err[2];
  if (pipe2(out, O_CLOEXEC) != 0 || pipe2(err, O_CLOEXEC) != 0) throw std::runtime_error("pipe");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork");
  if (pid == 0) {
    dup2(stdout_fd >= 0 ? stdout_fd : out[1], 1);
    dup2(err[1], 2);
    for (const std::string& e : env) putenv(const_cast<char*>(e.c_str()));
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    // The test runner may block signals; the daemon must start with a clean mask.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(out[1]);
  close(err[1]);
  out_fd = out[0];
  err_fd = err[0];
  return pid;
}

ProcessResult collect(pid_t pid, int out_fd, int err_fd) {
  ProcessResult r;
  pollfd fds[2] = {{out_fd, POLLIN, 0}, {err_fd, POLLIN, 0}};
  int open_fds = 0;
  for (const pollfd& f : fds) open_fds += f.fd >= 0 ? 1 : 0;
  char buf[4096];
  while (open_fds > 0) {
    if (poll(fds, 2, -1) < 0) continue;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP))) continue;
      const ssize_t n = read(fds[i].fd, buf, sizeof buf);
      if (n > 0) {
        (i == 0 ? r.out : r.err).append(buf, static_cast<std::size_t>(n));
      } else {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  int status = 0;
  waitpid(pid, &status, 0);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace

ProcessResult run_process(const std::vector<std::string>& args,
                          const std::vector<std::string>& env) {
  int out_fd = -1, err_fd = -1;
  const pid_t pid = spawn(args, env, out_fd, err_fd);
  return collect(pid, out_fd, err_fd);
}

ProcessResult run_process_with_stdout(const std::vector<std::string>& args,
                                      const std::string& stdout_path) {
  const int fd = open(stdout_path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("open " + stdout_path);
  int out_fd = -1, err_fd = -1;
  const pid_t pid = spawn(args, {}, out_fd, err_fd, fd);
  close(fd);
  return collect(pid, out_fd, err_fd);
}

BackgroundProcess::BackgroundProcess(const std::vector<std::string>& args,
                                     const std::vector<std::string>& env)
    : comm_(std::filesystem::path(args.at(0)).filename().string().substr(0, 15)) {
  pid_ = spawn(args, env, out_fd_, err_fd_);
}

BackgroundProcess::~BackgroundProcess() {
  if (pid_ > 0) {
    kill(pid_, SIGKILL);
    wait();
  }
}

void BackgroundProcess::signal(int sig) const { kill(pid_, sig); }

bool BackgroundProcess::wait_until_blocked(int sig, int timeout_ms) const {
  const std::string status_path = "/proc/" + std::to_string(pid_) + "/status";
  for (int waited = 0; waited < timeout_ms; ++waited) {
    std::ifstream in(status_path);
    std::string line;
    // Before its exec the child is still the test binary, whose mask may block everything
    // for a moment (ThreadSanitizer blocks all signals around fork): that is not the daemon.
    bool execed = false;
    while (std::getline(in, line)) {
      if (line.rfind("Name:", 0) == 0)
        execed = line.substr(line.find_first_not_of(" \t", 5)) == comm_;
      if (!execed || line.rfind("SigBlk:", 0) != 0) continue;
      const unsigned long long mask = std::stoull(line.substr(7), nullptr, 16);
      if (mask & (1ULL << (sig - 1))) return true;
    }
    if (!in.is_open() && waited > 0) return false;  // the process is gone
    usleep(1000);
  }
  return false;
}

void BackgroundProcess::close_output() {
  for (int* fd : {&out_fd_, &err_fd_}) {
    if (*fd >= 0) close(*fd);
    *fd = -1;
  }
}

ProcessResult BackgroundProcess::wait() {
  const ProcessResult r = collect(pid_, out_fd_, err_fd_);
  pid_ = -1;
  return r;
}

NotifySocket::NotifySocket() {
  static int counter = 0;
  path_ = temp_path("notify" + std::to_string(counter++) + ".sock");
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path_.c_str());
  if (fd_ < 0 || bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    throw std::runtime_error("notify socket " + path_);
  }
}

NotifySocket::~NotifySocket() {
  close(fd_);
  unlink(path_.c_str());
}

bool NotifySocket::wait_for(const std::string& text, int timeout_ms) {
  char buf[1024];
  pollfd p{fd_, POLLIN, 0};
  while (poll(&p, 1, timeout_ms) > 0) {
    const ssize_t n = recv(fd_, buf, sizeof buf, 0);
    if (n > 0 && std::string(buf, static_cast<std::size_t>(n)).find(text) != std::string::npos) {
      return true;
    }
  }
  return false;
}

std::string wait_ready(NotifySocket& notify, BackgroundProcess& p) {
  for (int waited_ms = 0; waited_ms < 30000; waited_ms += 100) {
    if (notify.wait_for("READY=1", 100)) return "";
    siginfo_t info{};  // WNOWAIT: p.wait() still collects it
    if (waitid(P_PID, static_cast<id_t>(p.pid()), &info, WEXITED | WNOHANG | WNOWAIT) == 0 &&
        info.si_pid == p.pid()) {
      break;  // ended without being ready
    }
  }
  p.signal(SIGKILL);
  const ProcessResult r = p.wait();
  return "never ready (exit " + std::to_string(r.exit_code) + "):\n" + r.err;
}

std::string hapticd_binary() { return HAPTICD_BINARY; }
std::string source_dir() { return HAPTICD_SOURCE_DIR; }
std::string example(const std::string& name) { return source_dir() + "/config/" + name; }
std::string coupling_example() { return example("coupling-example.yaml"); }
std::string build_dir() { return HAPTICD_BUILD_DIR; }

std::string temp_path(const std::string& name) {
  const char* base = std::getenv("TMPDIR");
  static const std::string dir = [&] {
    std::string d = std::string(base ? base : "/tmp") + "/hapticd-test-XXXXXX";
    if (mkdtemp(d.data()) == nullptr) throw std::runtime_error("mkdtemp");
    return d;
  }();
  return dir + "/" + name;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  const std::string tmp = path + ".tmp";
  std::ofstream(tmp) << text;
  std::filesystem::rename(tmp, path);
  return path;
}

}  // namespace hapticd::testing
