// vcu-web's logins (auth.hpp): crypt(3) hashes through libxcrypt, the users file, sessions
// and the failed-login limit.
#include "auth.hpp"

#include <crypt.h>
#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>
#include <span>

#include "openvcu/config/json.hpp"
#include "openvcu/core/input_file.hpp"

namespace openvcu::web {
namespace {

using config::Json;
using config::JsonChecker;

/// The users file is small (a line per user); anything larger is a mistake or an attack.
constexpr input::FileKind USERS_FILE{"users file", std::uint64_t{1} << 20};
constexpr std::size_t MAX_NAME_LENGTH = 32;
constexpr std::size_t SALT_RANDOM_BYTES = 16;  // libxcrypt's recommendation for yescrypt
constexpr std::size_t TOKEN_BYTES = 32;        // 256 bits, 64 hex digits
/// Addresses with failed logins kept before stale ones are swept out (bounds the map).
constexpr std::size_t FAILURE_SWEEP_THRESHOLD = 1024;

/// A yescrypt hash (libxcrypt's default cost "j9T") of a password nobody knows, checked for an
/// unknown user so that the answer takes as long as for a known one.
constexpr const char* DUMMY_HASH = "$y$j9T$obvBnZVTKMr0wltDt0yiN.$Q6cuJ9xOxDlNeVTocFOfPGxxAs2Wlj.dOyts3v4cTrD";

/// The hash methods accepted in a users file, by prefix, with the length of the part after
/// the last '$' (the checksum; for bcrypt the salt and checksum together).
struct HashMethod {
  std::string_view prefix;
  std::size_t tailLength;
  std::string_view name;
};
constexpr std::array<HashMethod, 4> HASH_METHODS{{
    {"$y$", 43, "yescrypt"},
    {"$6$", 86, "SHA-512"},
    {"$5$", 43, "SHA-256"},
    {"$2b$", 53, "bcrypt"},
}};

/// Fills `out` from the kernel's random source (getrandom(2); blocks only before the pool is
/// initialised at boot). A kernel that cannot give random bytes cannot host logins: ends the
/// process with a message rather than hand out guessable salts or tokens.
void fillRandom(std::span<unsigned char> out) {
  std::size_t filled = 0;
  while (filled < out.size()) {
    const ssize_t got = ::getrandom(out.data() + filled, out.size() - filled, 0);
    if (got < 0) {
      if (errno == EINTR) continue;
      std::fprintf(stderr, "vcu-web: error: getrandom failed: %s\n", std::strerror(errno));
      std::abort();
    }
    filled += static_cast<std::size_t>(got);
  }
}

std::string randomToken() {
  std::array<unsigned char, TOKEN_BYTES> bytes{};
  fillRandom(bytes);
  static constexpr char HEX[] = "0123456789abcdef";
  std::string token;
  token.reserve(TOKEN_BYTES * 2);
  for (const unsigned char byte : bytes) {
    token.push_back(HEX[byte >> 4]);
    token.push_back(HEX[byte & 0x0f]);
  }
  return token;
}

bool validUserName(std::string_view name) noexcept {
  if (name.empty() || name.size() > MAX_NAME_LENGTH) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
           c == '-';
  });
}

const std::string USER_NAME_FORM = "1-32 of A-Z a-z 0-9 . _ -";

/// Empty when `hash` looks like a complete hash of an accepted method, else the reason.
std::string hashProblem(const std::string& hash) {
  const auto method = std::find_if(HASH_METHODS.begin(), HASH_METHODS.end(),
                                   [&](const HashMethod& m) { return hash.starts_with(m.prefix); });
  if (method == HASH_METHODS.end()) {
    return "not a crypt(3) hash of an accepted method (yescrypt \"$y$\", SHA-512 \"$6$\", SHA-256 \"$5$\", "
           "bcrypt \"$2b$\"); make one with vcu-web passwd";
  }
  const std::size_t lastDollar = hash.rfind('$');
  const std::size_t tail = hash.size() - lastDollar - 1;
  const int check = ::crypt_checksalt(hash.c_str());
  const bool characters =
      std::all_of(hash.begin() + static_cast<std::ptrdiff_t>(lastDollar) + 1, hash.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '/';
      });
  if (lastDollar < method->prefix.size() || tail != method->tailLength || !characters ||
      (check != CRYPT_SALT_OK && check != CRYPT_SALT_METHOD_LEGACY)) {
    return "not a complete " + std::string(method->name) + " hash";
  }
  return {};
}

/// crypt_rn into `data`; nullptr when crypt refuses the setting (or marks its output invalid).
const char* runCrypt(const std::string& password, const char* setting, crypt_data& data) {
  const char* output = ::crypt_rn(password.c_str(), setting, &data, static_cast<int>(sizeof(data)));
  if (output == nullptr || output[0] == '*') return nullptr;
  return output;
}

bool constantTimeEqual(std::string_view a, std::string_view b) noexcept {
  if (a.size() != b.size()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    difference =
        static_cast<unsigned char>(difference | (static_cast<unsigned char>(a[i]) ^ static_cast<unsigned char>(b[i])));
  }
  return difference == 0;
}

/// The checked users of a parsed document (errors: file, JSON path, reason).
Result<std::vector<User>> readUsers(const Json& root, const std::string& source) {
  JsonChecker check(source);
  if (!check.isObject(root, "")) return check.firstError();
  check.onlyKeys(root, "", {"users", "comment"});
  std::vector<User> users;
  std::set<std::string, std::less<>> seen;
  if (const Json* list = check.array(root, "", "users")) {
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string where = JsonChecker::join("/users", i);
      const Json& item = (*list)[i];
      if (!check.isObject(item, where)) continue;
      check.onlyKeys(item, where, {"name", "hash", "comment"});
      check.string(item, where, "comment", false);
      auto name = check.string(item, where, "name");
      auto hash = check.string(item, where, "hash");
      if (name && !validUserName(*name)) {
        check.error(JsonChecker::join(where, "name"), "'" + *name + "' is not a user name (" + USER_NAME_FORM + ")");
        name.reset();
      }
      if (name && !seen.insert(*name).second) {
        check.error(JsonChecker::join(where, "name"), "user '" + *name + "' is given twice");
        name.reset();
      }
      if (hash) {
        if (std::string problem = hashProblem(*hash); !problem.empty()) {
          check.error(JsonChecker::join(where, "hash"), std::move(problem));
          hash.reset();
        }
      }
      if (name && hash) users.push_back(User{std::move(*name), std::move(*hash)});
    }
  }
  if (!check.ok()) return check.firstError();
  return users;
}

/// Writes `text` to `path` through a temporary file in the same folder (fsync, rename, fsync
/// of the folder). A new file gets mode 0600; a replaced one keeps its owner, group and
/// permission bits (without the "others" bits), so a file shared with vcu-web's group stays
/// readable to it.
Status writeUsersFile(const std::string& path, const std::string& text) {
  const std::filesystem::path target(path);
  const std::string folder = target.parent_path().empty() ? "." : target.parent_path().string();
  std::string temporary = folder + "/.";  // hidden beside the file: "dir/.web-users.json.XXXXXX"
  temporary += target.filename().string();
  temporary += ".XXXXXX";
  const int fd = ::mkstemp(temporary.data());  // mode 0600
  if (fd < 0)
    return Error{"cannot write the users file: " + std::string(std::strerror(errno)), Location{path, 0, 0, {}}};
  const auto fail = [&](const std::string& what) -> Status {
    const int saved = errno;
    ::close(fd);
    ::unlink(temporary.c_str());
    return Error{"cannot " + what + " the users file: " + std::string(std::strerror(saved)), Location{path, 0, 0, {}}};
  };
  struct stat existing {};
  if (::stat(path.c_str(), &existing) == 0) {
    if (::fchown(fd, existing.st_uid, existing.st_gid) != 0) {
      // not root: the file stays ours; its group may be lost, the mode is still copied
    }
    if (::fchmod(fd, existing.st_mode & 0770) != 0) return fail("write");
  }
  std::string_view rest(text);
  while (!rest.empty()) {
    const ssize_t written = ::write(fd, rest.data(), rest.size());
    if (written < 0) {
      if (errno == EINTR) continue;
      return fail("write");
    }
    rest.remove_prefix(static_cast<std::size_t>(written));
  }
  if (::fsync(fd) != 0) return fail("write");
  if (::close(fd) != 0) {
    const int saved = errno;
    ::unlink(temporary.c_str());
    return Error{"cannot write the users file: " + std::string(std::strerror(saved)), Location{path, 0, 0, {}}};
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const int saved = errno;
    ::unlink(temporary.c_str());
    return Error{"cannot replace the users file: " + std::string(std::strerror(saved)), Location{path, 0, 0, {}}};
  }
  const int folderFd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (folderFd >= 0) {
    ::fsync(folderFd);
    ::close(folderFd);
  }
  return {};
}

}  // namespace

// ---- hashes -----------------------------------------------------------------------------

Result<std::string> hashPassword(std::string_view password) {
  if (password.empty()) return Error{"the password is empty"};
  if (password.find('\0') != std::string_view::npos) return Error{"the password contains a NUL byte"};
  if (password.size() >= CRYPT_MAX_PASSPHRASE_SIZE) {
    return Error{"the password is too long (at most " + std::to_string(CRYPT_MAX_PASSPHRASE_SIZE - 1) + " bytes)"};
  }
  std::array<unsigned char, SALT_RANDOM_BYTES> random{};
  fillRandom(random);
  std::array<char, CRYPT_GENSALT_OUTPUT_SIZE> setting{};
  if (::crypt_gensalt_rn("$y$", 0, reinterpret_cast<const char*>(random.data()), static_cast<int>(random.size()),
                         setting.data(), static_cast<int>(setting.size())) == nullptr) {
    return Error{"cannot make a yescrypt salt: " + std::string(std::strerror(errno))};
  }
  auto data = std::make_unique<crypt_data>();  // ~32 KiB: not on a worker thread's stack
  const char* output = runCrypt(std::string(password), setting.data(), *data);
  if (output == nullptr) return Error{"crypt refused to hash the password: " + std::string(std::strerror(errno))};
  return std::string(output);
}

bool verifyPassword(std::string_view password, const std::string& hash) {
  if (password.find('\0') != std::string_view::npos || password.size() >= CRYPT_MAX_PASSPHRASE_SIZE) return false;
  if (hash.empty() || hash[0] != '$') return false;  // never the DES fallback of a bare salt
  auto data = std::make_unique<crypt_data>();
  const char* output = runCrypt(std::string(password), hash.c_str(), *data);
  if (output == nullptr) return false;
  return constantTimeEqual(output, hash);
}

// ---- users file -------------------------------------------------------------------------

Result<UserFile> UserFile::load(const std::string& path) {
  Result<std::string> text = input::readWholeFile(path, USERS_FILE);
  if (!text) return text.error();
  return parse(*text, path);
}

Result<UserFile> UserFile::parse(std::string_view text, const std::string& source) {
  Result<Json> document = config::parseJson(text, source);
  if (!document) return document.error();
  Result<std::vector<User>> users = readUsers(*document, source);
  if (!users) return users.error();
  UserFile file;
  file.m_users = std::move(*users);
  return file;
}

const User* UserFile::find(std::string_view name) const noexcept {
  const auto found = std::find_if(m_users.begin(), m_users.end(), [&](const User& user) { return user.name == name; });
  return found == m_users.end() ? nullptr : &*found;
}

Status UserFile::setPassword(const std::string& path, std::string_view name, std::string_view password) {
  if (!validUserName(name)) return Error{"'" + std::string(name) + "' is not a user name (" + USER_NAME_FORM + ")"};
  // The document as it is (comments of users and unknown-to-us order kept), checked whole
  // first: a broken file is reported, never overwritten.
  Json document = Json::object({{"users", Json::array()}});
  std::error_code missing;
  const auto status = std::filesystem::symlink_status(path, missing);
  if (!missing && status.type() != std::filesystem::file_type::not_found) {
    Result<std::string> text = input::readWholeFile(path, USERS_FILE);
    if (!text) return text.error();
    Result<Json> parsed = config::parseJson(*text, path);
    if (!parsed) return parsed.error();
    if (Result<std::vector<User>> users = readUsers(*parsed, path); !users) return users.error();
    document = std::move(*parsed);
  } else if (missing && missing != std::errc::no_such_file_or_directory) {
    return Error{"cannot read the users file: " + missing.message(), Location{path, 0, 0, {}}};
  }
  Result<std::string> hash = hashPassword(password);
  if (!hash) return hash.error();
  Json& users = document["users"];
  const auto existing = std::find_if(users.begin(), users.end(), [&](const Json& user) {
    return user.at("name").get_ref<const std::string&>() == name;
  });
  if (existing != users.end()) {
    (*existing)["hash"] = *hash;
  } else {
    users.push_back(Json::object({{"name", std::string(name)}, {"hash", *hash}}));
  }
  // A users file reached through a symlink is replaced where it lives; the link stays.
  std::string target = path;
  if (status.type() == std::filesystem::file_type::symlink) {
    std::error_code resolveError;
    const auto resolved = std::filesystem::canonical(path, resolveError);
    if (resolveError)
      return Error{"cannot resolve the users file: " + resolveError.message(), Location{path, 0, 0, {}}};
    target = resolved.string();
  }
  return writeUsersFile(target, document.dump(2) + "\n");
}

// ---- sessions ---------------------------------------------------------------------------

Sessions::Sessions(std::chrono::seconds lifetime, std::size_t maxSessions, int maxFailures,
                   std::chrono::seconds failureWindow)
    : m_lifetime(lifetime),
      m_maxSessions(std::max<std::size_t>(maxSessions, 1)),
      m_maxFailures(std::max(maxFailures, 1)),
      m_failureWindow(failureWindow) {}

bool Sessions::checkPassword(const UserFile& users, std::string_view user, std::string_view password) {
  const User* known = users.find(user);
  if (known == nullptr) {
    (void)verifyPassword(password, DUMMY_HASH);  // the same work as for a known user
    return false;
  }
  return verifyPassword(password, known->hash);
}

std::optional<Session> Sessions::login(const UserFile& users, std::string_view user, std::string_view password,
                                       const std::string& clientAddress, Clock::time_point now, LoginRefusal* refusal) {
  if (!beginLogin(clientAddress, now)) {
    if (refusal != nullptr) *refusal = LoginRefusal::TooManyAttempts;
    return std::nullopt;
  }
  std::optional<Session> session = completeLogin(user, checkPassword(users, user, password), clientAddress, now);
  if (!session && refusal != nullptr) *refusal = LoginRefusal::WrongUserOrPassword;
  return session;
}

bool Sessions::beginLogin(const std::string& clientAddress, Clock::time_point now) {
  if (retryAfter(clientAddress, now).count() > 0) return false;
  if (m_failures.size() >= FAILURE_SWEEP_THRESHOLD) {
    std::erase_if(m_failures, [&](const auto& entry) {
      return entry.second.empty() || entry.second.back() + m_failureWindow <= now;
    });
  }
  std::vector<Clock::time_point>& times = m_failures[clientAddress];
  // Only the last maxFailures attempts decide a refusal; older ones are dropped.
  std::erase_if(times, [&](Clock::time_point t) { return t + m_failureWindow <= now; });
  if (times.size() >= static_cast<std::size_t>(m_maxFailures)) times.erase(times.begin());
  times.push_back(now);  // a failure until completeLogin() says otherwise
  return true;
}

std::optional<Session> Sessions::completeLogin(std::string_view user, bool passwordOk, const std::string& clientAddress,
                                               Clock::time_point now) {
  if (!passwordOk) return std::nullopt;
  m_failures.erase(clientAddress);
  std::erase_if(m_sessions, [&](const auto& entry) { return entry.second.expires <= now; });
  while (m_sessions.size() >= m_maxSessions) {
    // the session unused for longest (all have the same lifetime) makes room
    const auto oldest = std::min_element(m_sessions.begin(), m_sessions.end(), [](const auto& a, const auto& b) {
      return a.second.expires < b.second.expires;
    });
    m_sessions.erase(oldest);
  }
  Session session{randomToken(), std::string(user), now + m_lifetime};
  m_sessions.emplace(session.token, session);
  return session;
}

const Session* Sessions::find(std::string_view token, Clock::time_point now) {
  const auto found = m_sessions.find(token);
  if (found == m_sessions.end()) return nullptr;
  if (found->second.expires <= now) {
    m_sessions.erase(found);
    return nullptr;
  }
  found->second.expires = now + m_lifetime;
  return &found->second;
}

void Sessions::logout(std::string_view token) {
  if (const auto found = m_sessions.find(token); found != m_sessions.end()) m_sessions.erase(found);
}

std::chrono::seconds Sessions::retryAfter(const std::string& clientAddress, Clock::time_point now) const {
  const auto found = m_failures.find(clientAddress);
  if (found == m_failures.end()) return std::chrono::seconds(0);
  const std::vector<Clock::time_point>& times = found->second;
  const auto recent =
      std::count_if(times.begin(), times.end(), [&](Clock::time_point t) { return t + m_failureWindow > now; });
  if (recent < m_maxFailures) return std::chrono::seconds(0);
  // refused until the oldest of the last maxFailures attempts leaves the window (rounded up)
  const Clock::time_point freeAt = times[times.size() - static_cast<std::size_t>(m_maxFailures)] + m_failureWindow;
  return std::chrono::ceil<std::chrono::seconds>(freeAt - now);
}

}  // namespace openvcu::web
