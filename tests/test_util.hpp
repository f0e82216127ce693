// Helpers shared by the test files that run the solver whole: running the
// mmpm binary (fork/exec, stdout/stderr captured through pipes), scratch
// directories, small file helpers and scene-text builders.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace mmpm_test {

namespace fs = std::filesystem;

inline std::string source_dir() {
  return MMPM_SOURCE_DIR;
}
inline std::string mmpm_binary() {
  return MMPM_BINARY;
}

// ------------------------------------------------------------------ files --

inline std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_text(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write " + file.string());
  out << text;
}

// A fresh directory per test (named after the test and the pid), removed afterwards.
class TempDir {
 public:
  explicit TempDir(const std::string& tag = "") {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "mmpm_test_";
    if (info) name += std::string(info->test_suite_name()) + "_" + info->name() + "_";
    name += tag + (tag.empty() ? "" : "_") + std::to_string(::getpid());
    for (char& c : name)
      if (c == '/') c = '_';
    path_ = fs::temp_directory_path() / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& rel) const { return path_ / rel; }
  std::string str() const { return path_.string(); }

 private:
  fs::path path_;
};

// -------------------------------------------------------------- processes --

struct CmdResult {
  int exit_code = -1;  // exit status, or -1 when killed by a signal
  int signal = 0;      // the signal that ended it, 0 if it exited
  std::string out, err;
  double seconds = 0;  // wall time
  std::string describe() const {
    std::ostringstream s;
    s << "exit " << exit_code << (signal ? " signal " + std::to_string(signal) : std::string())
      << "\n--- stdout ---\n"
      << out << "--- stderr ---\n"
      << err;
    return s.str();
  }
};

namespace detail {
inline std::vector<char*> argv_of(std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return argv;
}

// In the child after fork: only async-signal-safe calls until exec.
[[noreturn]] inline void exec_child(std::vector<char*>& argv, const char* cwd, int out_fd,
                                    int err_fd) {
  if (out_fd >= 0) ::dup2(out_fd, STDOUT_FILENO);
  if (err_fd >= 0) ::dup2(err_fd, STDERR_FILENO);
  const int devnull = ::open("/dev/null", O_RDONLY);
  if (devnull >= 0) ::dup2(devnull, STDIN_FILENO);
  if (cwd && ::chdir(cwd) != 0) ::_exit(127);
  ::execv(argv[0], argv.data());
  ::_exit(127);
}

inline void decode_status(int status, CmdResult& r) {
  if (WIFEXITED(status)) {
    r.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    r.signal = WTERMSIG(status);
  }
}
}  // namespace detail

// Runs args[0] (a path) with args[1..], stdout and stderr captured, stdin
// from /dev/null, in `cwd` (empty: this process's working directory).
inline CmdResult run_command(std::vector<std::string> args, const std::string& cwd = "") {
  CmdResult r;
  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0 || ::pipe(err_pipe) != 0) throw std::runtime_error("pipe failed");
  auto argv = detail::argv_of(args);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    detail::exec_child(argv, cwd.empty() ? nullptr : cwd.c_str(), out_pipe[1], err_pipe[1]);
  }
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&r.out, &r.err};
  int open_count = 2;
  char buf[65536];
  while (open_count > 0) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t got = ::read(fds[k].fd, buf, sizeof buf);
      if (got > 0) {
        sinks[k]->append(buf, std::size_t(got));
      } else if (got == 0 || errno != EINTR) {
        ::close(fds[k].fd);
        fds[k].fd = -1;
        --open_count;
      }
    }
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  detail::decode_status(status, r);
  return r;
}

// `mmpm ARGS...` through the real binary.
inline CmdResult run_mmpm(const std::vector<std::string>& args, const std::string& cwd = "") {
  std::vector<std::string> all{mmpm_binary()};
  all.insert(all.end(), args.begin(), args.end());
  return run_command(all, cwd);
}

// A child process left running (stdout/stderr to files), for kill tests.
class Child {
 public:
  Child(std::vector<std::string> args, const fs::path& out_file, const fs::path& err_file) {
    auto argv = detail::argv_of(args);
    const int out_fd = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out_fd < 0 || err_fd < 0) throw std::runtime_error("cannot open the child's log files");
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) detail::exec_child(argv, nullptr, out_fd, err_fd);
    ::close(out_fd);
    ::close(err_fd);
  }
  ~Child() {
    if (pid_ > 0 && !reaped_) {
      ::kill(pid_, SIGKILL);
      int status;
      ::waitpid(pid_, &status, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  // True (and the result filled) once the child has ended.
  bool poll_done() {
    if (reaped_) return true;
    int status = 0;
    const pid_t w = ::waitpid(pid_, &status, WNOHANG);
    if (w == pid_) {
      reaped_ = true;
      detail::decode_status(status, result_);
    }
    return reaped_;
  }
  void kill_and_wait(int sig) {
    if (reaped_) return;
    ::kill(pid_, sig);
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    reaped_ = true;
    detail::decode_status(status, result_);
  }
  const CmdResult& result() const { return result_; }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  bool reaped_ = false;
  CmdResult result_;
};

// ---------------------------------------------------------------- strings --

inline bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

inline std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Non-empty lines of a text.
inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) out.push_back(line);
  return out;
}

// 1-based line number of the first line of `text` containing `needle` (0 if none).
inline int line_of(const std::string& text, const std::string& needle) {
  std::istringstream in(text);
  std::string line;
  int k = 0;
  while (std::getline(in, line)) {
    ++k;
    if (contains(line, needle)) return k;
  }
  return 0;
}

// ----------------------------------------------------------------- scenes --

// Parameters of a rectangular 2D test scene: one or two boxes of elastic
// material on a grid with a margin of empty cells around them.
struct BoxScene2D {
  std::string precision = "double";
  std::string shape = "gimp";
  std::string scheme = "USL";
  double end_time = 1.0;
  double cfl = 0.5;
  double cell = 1.0;
  int cells_x = 110, cells_y = 90;
  int ppc = 2;
  // Body 0 always; body 1 only when two_bodies.
  double b0_min[2] = {4.0, 4.0}, b0_max[2] = {54.0, 64.0};
  double b0_vel[2] = {0.0, 0.0};
  bool two_bodies = false;
  bool second_material = false;  // body 1 made of material "b" (else "a")
  double b1_min[2] = {54.0, 4.0}, b1_max[2] = {100.0, 64.0};
  double b1_vel[2] = {0.0, 0.0};
  std::string extra;  // appended verbatim (interactions, loads, boundaries, output...)

  std::string text() const {
    std::ostringstream s;
    s.precision(17);
    s << "[simulation]\ndimension = 2\nplane = \"strain\"\nthickness = 1.0\n"
      << "end_time = " << end_time << "\ncfl = " << cfl << "\nscheme = \"" << scheme << "\"\n"
      << "precision = \"" << precision << "\"\n\n"
      << "[grid]\norigin = [0.0, 0.0]\ncell = [" << cell << ", " << cell << "]\n"
      << "cells = [" << cells_x << ", " << cells_y << "]\nshape = \"" << shape << "\"\n\n"
      << "[[material]]\nname = \"a\"\ntype = \"isotropic\"\ndensity = 1.0e-3\nE = 1000.0\nnu = "
         "0.3\n\n";
    if (second_material)
      s << "[[material]]\nname = \"b\"\ntype = \"isotropic\"\ndensity = 2.0e-3\nE = 3000.0\nnu = "
           "0.25\n\n";
    s << "[[body]]\nname = \"left\"\nmaterial = \"a\"\nshape = \"box\"\n"
      << "min = [" << b0_min[0] << ", " << b0_min[1] << "]\nmax = [" << b0_max[0] << ", "
      << b0_max[1] << "]\nparticles_per_cell = " << ppc << "\nvelocity = [" << b0_vel[0] << ", "
      << b0_vel[1] << "]\n\n";
    if (two_bodies)
      s << "[[body]]\nname = \"right\"\nmaterial = \"" << (second_material ? "b" : "a")
        << "\"\nshape = \"box\"\n"
        << "min = [" << b1_min[0] << ", " << b1_min[1] << "]\nmax = [" << b1_max[0] << ", "
        << b1_max[1] << "]\nparticles_per_cell = " << ppc << "\nvelocity = [" << b1_vel[0] << ", "
        << b1_vel[1] << "]\n\n";
    s << extra;
    return s.str();
  }
};

}  // namespace mmpm_test
