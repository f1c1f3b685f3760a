#include "pc_server/foxglove/token_file.hpp"

#include <fcntl.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "shared/util/startup_error.hpp"
#include "shared/util/log.hpp"

namespace inspect::server::foxglove {

std::string loadOrCreateToken(const std::string& path) {
  const std::string what = "foxglove token file '" + path + "': ";
  struct stat st{};
  if (::stat(path.c_str(), &st) == 0) {
    std::ifstream in(path);
    std::string token;
    if (!in || !std::getline(in, token)) throw util::StartupError(what + "cannot read it");
    while (!token.empty() && (token.back() == '\r' || token.back() == ' ' || token.back() == '\t')) token.pop_back();
    if (token.size() < 16 || token.size() > 256)
      throw util::StartupError(what + "the token must be 16 to 256 characters (it has " + std::to_string(token.size()) + ")");
    for (const unsigned char c : token)
      if (c <= ' ' || c >= 0x7f || c == '&' || c == '#' || c == '?' || c == '%')
        throw util::StartupError(what + "the token must be printable ASCII without spaces, &, #, ? or %");
    if ((st.st_mode & 077) != 0) {
      char mode[8];
      std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(st.st_mode & 0777));
      log::warn("foxglove", path, " has mode ", mode, ": other users may read the token; chmod 600 it");
    }
    return token;
  }
  if (errno != ENOENT) throw util::StartupError(what + std::strerror(errno));
  unsigned char raw[16];
  if (RAND_bytes(raw, sizeof raw) != 1) throw util::StartupError(what + "no random bytes from OpenSSL");
  std::string token;
  for (const unsigned char b : raw) {
    token += "0123456789abcdef"[b >> 4];
    token += "0123456789abcdef"[b & 15];
  }
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw util::StartupError(what + "cannot create it: " + std::strerror(errno));
  const std::string line = token + "\n";
  const bool ok = ::write(fd, line.data(), line.size()) == static_cast<ssize_t>(line.size());
  ::close(fd);
  if (!ok) throw util::StartupError(what + "cannot write it");
  log::info("foxglove", "new token written to ", path);
  return token;
}

}  // namespace inspect::server::foxglove
