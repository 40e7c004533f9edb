#pragma once
// Who may command the VCU from a browser (docs/design/web.md, "Logins"): the users file named
// in web.json, password checks against crypt(3) hashes (libxcrypt: yescrypt "$y$" by default,
// SHA-512 "$6$" accepted), sessions that expire, and a limit on failed logins.
//
// The users file (JSON, mode 0600 or 0640 recommended):
//   {"users": [{"name": "alice", "hash": "$y$j9T$...", "comment": "bench engineer"}]}
// `vcu-web passwd --users FILE NAME` adds or replaces a user (the password read from stdin
// or the terminal), written atomically.
//
//   auto usersResult = web::UserFile::load("/etc/openvcu/web-users.json");  // errors: file, JSON path, reason
//   web::Sessions sessions(std::chrono::minutes(60));
//   auto login = sessions.login(*usersResult, "alice", "secret", "127.0.0.1", now);
//   if (login) cookie = login->token;                     // 256 random bits, hex
//   const web::Session* who = sessions.find(token, now);  // nullptr: unknown or expired

#include <chrono>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::web {

struct User {
  std::string name;  ///< 1-32 of [A-Za-z0-9._-]
  std::string hash;  ///< a crypt(3) hash
};

/// The users file, loaded and checked.
class UserFile {
 public:
  /// An error names the file and the JSON path ("web-users.json: /users/1/hash: not a crypt(3) hash").
  /// A missing file is an error too; the caller decides whether that means "read-only".
  static Result<UserFile> load(const std::string& path);
  static Result<UserFile> parse(std::string_view text, const std::string& source);
  [[nodiscard]] const User* find(std::string_view name) const noexcept;
  [[nodiscard]] const std::vector<User>& users() const noexcept { return m_users; }
  /// Adds or replaces `name` with a hash of `password` and writes the file atomically
  /// (creating it, mode 0600). Errors: bad name, empty password, unwritable file.
  static Status setPassword(const std::string& path, std::string_view name, std::string_view password);

 private:
  std::vector<User> m_users;
};

/// A new crypt(3) hash of `password` (yescrypt, random salt from the kernel).
Result<std::string> hashPassword(std::string_view password);
/// True when `password` matches `hash` (constant-time compare of the crypt output).
[[nodiscard]] bool verifyPassword(std::string_view password, const std::string& hash);

struct Session {
  std::string token;  ///< 64 hex digits
  std::string user;
  std::chrono::steady_clock::time_point expires;
};

/// Open sessions and failed-login limits.
/// @note not thread-safe: lives on vcu-web's io thread (password checks are ~50 ms of CPU with
///       yescrypt: the caller may split login() into beginLogin() on the io thread,
///       checkPassword() on a worker and completeLogin() back on the io thread).
class Sessions {
 public:
  using Clock = std::chrono::steady_clock;
  /// `lifetime`: a session ends this long after its last use. At most `maxSessions` at once
  /// (the oldest is dropped). After `maxFailures` failed logins from one address within
  /// `failureWindow`, logins from that address are refused until the window has passed.
  explicit Sessions(std::chrono::seconds lifetime, std::size_t maxSessions = 256, int maxFailures = 5,
                    std::chrono::seconds failureWindow = std::chrono::seconds(60));

  enum class LoginRefusal { WrongUserOrPassword, TooManyAttempts };
  /// Checks the password (unknown user and wrong password are the same answer, and take
  /// the same time: a dummy hash is checked for an unknown user). A new session on success.
  [[nodiscard]] std::optional<Session> login(const UserFile& users, std::string_view user, std::string_view password,
                                             const std::string& clientAddress, Clock::time_point now,
                                             LoginRefusal* refusal = nullptr);
  /// login() in three steps, for a caller that checks passwords on a worker thread:
  ///   if (!sessions.beginLogin(address, now)) -> 429 (retryAfter(address, now))
  ///   bool ok = Sessions::checkPassword(users, user, password);   // any thread
  ///   auto session = sessions.completeLogin(user, ok, address, now);  // nullopt -> 401
  /// beginLogin() counts the attempt as failed until completeLogin() reports success, so
  /// attempts running in parallel use up the address's allowance too.
  [[nodiscard]] bool beginLogin(const std::string& clientAddress, Clock::time_point now);
  [[nodiscard]] std::optional<Session> completeLogin(std::string_view user, bool passwordOk,
                                                     const std::string& clientAddress, Clock::time_point now);
  /// True when `user` exists and `password` matches its hash; an unknown user costs the same
  /// time (a dummy yescrypt hash is checked). @note thread-safe (reads `users` only).
  [[nodiscard]] static bool checkPassword(const UserFile& users, std::string_view user, std::string_view password);
  /// The session of `token`, its expiry pushed out, or nullptr when unknown or expired.
  const Session* find(std::string_view token, Clock::time_point now);
  void logout(std::string_view token);
  /// Seconds until a refused address may try again (0: may try now).
  [[nodiscard]] std::chrono::seconds retryAfter(const std::string& clientAddress, Clock::time_point now) const;
  [[nodiscard]] std::size_t size() const noexcept { return m_sessions.size(); }
  [[nodiscard]] std::chrono::seconds lifetime() const noexcept { return m_lifetime; }

 private:
  std::chrono::seconds m_lifetime;
  std::size_t m_maxSessions;
  int m_maxFailures;
  std::chrono::seconds m_failureWindow;
  std::map<std::string, Session, std::less<>> m_sessions;
  std::map<std::string, std::vector<Clock::time_point>> m_failures;
};

/// `vcu-web passwd --users FILE NAME`: sets NAME's password in FILE (UserFile::setPassword).
/// `argv` as main() received it (argv[1] == "passwd"). The password is one line of stdin;
/// when stdin is a terminal it is asked twice without echo. Returns the exit code: 0 written,
/// 1 error (one line "vcu-web: error: ..." on stderr), 2 usage (the usage on stderr).
int runPasswdCommand(int argc, char** argv);

}  // namespace openvcu::web
