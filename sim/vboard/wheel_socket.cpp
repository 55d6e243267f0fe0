#include "sim/vboard/wheel_socket.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "sim/vboard/virtual_board.hpp"

namespace mc::sim {

namespace {

// A request line is short; a longer one is not ours.
constexpr size_t kMaxLine = 128;
// How long serve() waits for a connected client's line.
constexpr int kLineWaitMs = 100;

std::runtime_error sys_error(const std::string& what, const std::string& path) {
  return std::runtime_error(what + " " + path + ": " + std::strerror(errno));
}

sockaddr_un address(const std::string& path) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.size() >= sizeof a.sun_path)
    throw std::runtime_error("socket path " + path + " is longer than " +
                             std::to_string(sizeof a.sun_path - 1) +
                             " bytes (set XDG_RUNTIME_DIR to a shorter directory)");
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  return a;
}

// One line from fd, without its newline; empty when none came within
// wait_ms (-1: no limit) or it was too long.
std::string read_line(int fd, int wait_ms) {
  std::string line;
  char c = 0;
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, wait_ms) <= 0 || ::read(fd, &c, 1) != 1) return "";
    if (c == '\n') return line;
    line += c;
    if (line.size() > kMaxLine) return "";
  }
}

void write_line(int fd, const std::string& s) {
  const std::string line = s + "\n";
  // The client may be gone; nothing to tell then (SIGPIPE: MSG_NOSIGNAL).
  (void)::send(fd, line.data(), line.size(), MSG_NOSIGNAL);
}

}  // namespace

WheelSocket::WheelSocket(std::string path) : path_(std::move(path)) {
  const sockaddr_un a = address(path_);
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw sys_error("socket for", path_);
  // A server that was killed leaves its socket file behind; a live one
  // owns its own path (named after its pseudo-terminal), so this one is stale.
  ::unlink(path_.c_str());
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 || ::listen(fd_, 8) != 0) {
    const std::runtime_error e = sys_error("cannot listen on", path_);
    ::close(fd_);
    throw e;
  }
}

WheelSocket::~WheelSocket() {
  for (const Waiting& w : waiting_) ::close(w.fd);
  ::close(fd_);
  ::unlink(path_.c_str());
}

bool WheelSocket::serve(VirtualBoard& board) {
  bool asked = false;
  for (int c; (c = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC)) >= 0;) {
    asked = true;
    std::istringstream in(read_line(c, kLineWaitMs));
    std::string word;
    int detents = 0;
    double seconds = 0;
    if (!(in >> word >> detents >> seconds) || word != "wheel" || !(in >> std::ws).eof()) {
      write_line(c, "error: expected the line 'wheel DETENTS SECONDS'");
      ::close(c);
      continue;
    }
    try {
      board.turn_handwheel(detents, seconds);
    } catch (const std::exception& e) {
      write_line(c, std::string("error: ") + e.what());
      ::close(c);
      continue;
    }
    waiting_.push_back({c, board.handwheel_done_s()});
  }
  // Answered in the order asked: a later turn never ends before an earlier one.
  while (!waiting_.empty() && board.board_seconds() >= waiting_.front().done_s) {
    write_line(waiting_.front().fd, "ok");
    ::close(waiting_.front().fd);
    waiting_.erase(waiting_.begin());
  }
  return asked;
}

void request_wheel_turn(const std::string& path, int detents, double seconds) {
  const sockaddr_un a = address(path);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw sys_error("socket for", path);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const std::runtime_error e = sys_error("no virtual board listens on", path);
    ::close(fd);
    throw e;
  }
  std::ostringstream req;
  req.precision(17);
  req << "wheel " << detents << ' ' << seconds << '\n';
  const std::string r = req.str();
  const bool sent = ::send(fd, r.data(), r.size(), MSG_NOSIGNAL) == ssize_t(r.size());
  // The answer comes once the turn is done in board time: no limit here (a
  // slow engine takes longer in wall time), the server closing ends it.
  const std::string reply = sent ? read_line(fd, -1) : "";
  ::close(fd);
  if (reply == "ok") return;
  if (reply.rfind("error: ", 0) == 0)
    throw std::runtime_error("the virtual board refused the turn: " + reply.substr(7));
  throw std::runtime_error("the virtual board on " + path + " closed the connection without an answer");
}

}  // namespace mc::sim
