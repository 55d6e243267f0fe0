#include "host/link/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

namespace mc::host {

namespace {

speed_t baud_constant(long baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    case 1000000:
      return B1000000;
    case 2000000:
      return B2000000;
    case 3000000:
      return B3000000;
    default:
      throw LinkError("serial rate " + std::to_string(baud) + " bit/s is not supported");
  }
}

}  // namespace

SerialPort::SerialPort(const std::string& path, long baud) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int e = errno;
    if (e == ENOENT || e == ENODEV || e == ENXIO) throw LinkError("no such port " + path);
    if (e == EBUSY) throw LinkError("port " + path + " busy (another program has it open exclusively)");
    throw LinkError("cannot open port " + path + ": " + std::strerror(e));
  }
  // An advisory lock: two motionctl (or picocom, which locks the same way)
  // on one port would steal each other's replies.
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd_);
    throw LinkError("port " + path + " busy (another program has it open)");
  }
  termios tio{};
  if (::tcgetattr(fd_, &tio) != 0) {
    const int e = errno;
    ::close(fd_);
    throw LinkError("port " + path + " is not a serial port: " + std::strerror(e));
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~(CSTOPB | PARENB | CRTSCTS);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  const speed_t sp = baud_constant(baud);
  ::cfsetispeed(&tio, sp);
  ::cfsetospeed(&tio, sp);
  if (::tcsetattr(fd_, TCSANOW, &tio) != 0) {
    const int e = errno;
    ::close(fd_);
    throw LinkError("cannot set up port " + path + " (raw, " + std::to_string(baud) +
                    " bit/s): " + std::strerror(e));
  }
  ::tcflush(fd_, TCIFLUSH);
}

SerialPort::~SerialPort() {
  if (fd_ >= 0) ::close(fd_);
}

void SerialPort::write(const uint8_t* p, size_t n) {
  size_t at = 0;
  while (at < n) {
    const ssize_t k = ::write(fd_, p + at, n - at);
    if (k > 0) {
      at += size_t(k);
    } else if (k < 0 && (errno == EAGAIN || errno == EINTR)) {
      pollfd pf{fd_, POLLOUT, 0};
      ::poll(&pf, 1, 100);
    } else {
      throw LinkError("write to port " + path_ + " failed: " + std::strerror(errno));
    }
  }
}

size_t SerialPort::read(uint8_t* p, size_t n, std::chrono::milliseconds timeout) {
  pollfd pf{fd_, POLLIN, 0};
  const int r = ::poll(&pf, 1, int(timeout.count()));
  if (r < 0) {
    if (errno == EINTR) return 0;
    throw LinkError("poll on port " + path_ + " failed: " + std::strerror(errno));
  }
  if (r == 0) return 0;
  const ssize_t k = ::read(fd_, p, n);
  if (k > 0) return size_t(k);
  if (k < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
  if ((pf.revents & POLLHUP) || k == 0 || errno == EIO)
    throw LinkError("port " + path_ + " hung up (board unplugged, or the virtual board stopped)");
  throw LinkError("read from port " + path_ + " failed: " + std::strerror(errno));
}

// ---------------------------------------------------------------------------

FaultInjector::FaultInjector(ByteStream& inner, double flip_rate, double drop_rate, uint32_t seed)
    : inner_(inner), flip_(flip_rate), drop_(drop_rate), out_(seed), in_(seed ^ 0x9E3779B9u) {}

size_t FaultInjector::corrupt(Way& w, uint8_t* p, size_t n) {
  size_t kept = 0;
  w.n.bytes += n;
  for (size_t i = 0; i < n; ++i) {
    if (u_(w.rng) < drop_) {
      ++w.n.dropped;
      continue;
    }
    uint8_t b = p[i];
    if (u_(w.rng) < flip_) {
      b ^= uint8_t(1u << (w.rng() % 8));
      ++w.n.flipped;
    }
    p[kept++] = b;
  }
  return kept;
}

void FaultInjector::write(const uint8_t* p, size_t n) {
  std::vector<uint8_t> b(p, p + n);
  const size_t k = corrupt(out_, b.data(), n);
  if (k > 0) inner_.write(b.data(), k);
}

size_t FaultInjector::read(uint8_t* p, size_t n, std::chrono::milliseconds timeout) {
  return corrupt(in_, p, inner_.read(p, n, timeout));
}

}  // namespace mc::host
