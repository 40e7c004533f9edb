// vcu-web's logins (services/web/src/auth.hpp): hashes, the users file, sessions, the limit
// on failed logins and `vcu-web passwd`.
#include <doctest/doctest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "auth.hpp"

using namespace openvcu;
using namespace openvcu::web;
using namespace std::chrono_literals;

namespace {

/// A SHA-512 crypt(3) hash of "correct horse", made once with libxcrypt's crypt_rn and a
/// "$6$" salt from crypt_gensalt_rn (as `python3 -c "import crypt; crypt.crypt(...)"` would).
constexpr const char* SHA512_HASH =
    "$6$IVxBmB2j5n6FtWJq$P1PHMQTQwNTpixyMMta1zPnMXeRnMPnOV131LUv/nFReadCFRbvJsw0XWx91cW0r/ktH6lT8KH.jqFWFUgbnY1";
constexpr const char* SHA512_PASSWORD = "correct horse";
constexpr const char* CLIENT = "192.0.2.7";

/// A folder under the system's temporary folder with a random name, removed afterwards.
class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (std::filesystem::temp_directory_path() / "openvcu-web-auth-XXXXXX").string();
    if (::mkdtemp(pattern.data()) != nullptr) m_path = pattern;
  }
  ~TempFolder() {
    std::error_code ignored;
    if (!m_path.empty()) std::filesystem::remove_all(m_path, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  [[nodiscard]] std::string file(const std::string& name) const { return (m_path / name).string(); }

 private:
  std::filesystem::path m_path;
};

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

UserFile usersWithSha512(const char* name = "alice") {
  auto parsed = UserFile::parse(
      std::string(R"({"users": [{"name": ")") + name + R"(", "hash": ")" + SHA512_HASH + "\"}]}", "web-users.json");
  REQUIRE(parsed);
  return *parsed;
}

std::string parseError(const std::string& text) {
  auto parsed = UserFile::parse(text, "web-users.json");
  REQUIRE_FALSE(parsed);
  return parsed.error().toString();
}

}  // namespace

TEST_CASE("a new yescrypt hash verifies its password and refuses another") {
  auto hash = hashPassword("s3cret pass");
  REQUIRE(hash);
  CHECK(hash->starts_with("$y$"));
  CHECK(verifyPassword("s3cret pass", *hash));
  CHECK_FALSE(verifyPassword("s3cret pasS", *hash));
  CHECK_FALSE(verifyPassword("", *hash));
}

TEST_CASE("two hashes of one password differ by their random salt") {
  auto first = hashPassword("same");
  auto second = hashPassword("same");
  REQUIRE(first);
  REQUIRE(second);
  CHECK(*first != *second);
}

TEST_CASE("hashPassword refuses an empty password") {
  CHECK_FALSE(hashPassword(""));
}

TEST_CASE("a SHA-512 hash made elsewhere verifies") {
  CHECK(verifyPassword(SHA512_PASSWORD, SHA512_HASH));
  CHECK_FALSE(verifyPassword("correct horse battery", SHA512_HASH));
}

TEST_CASE("verifyPassword is false for a hash crypt refuses") {
  CHECK_FALSE(verifyPassword("x", "$6$ab!c$d"));
  CHECK_FALSE(verifyPassword("x", "plain"));
  CHECK_FALSE(verifyPassword("x", ""));
}

TEST_CASE("a users file with users of each accepted method loads") {
  const std::string text = std::string(R"({"comment": "bench", "users": [
    {"name": "alice", "hash": ")") +
                           SHA512_HASH + R"(", "comment": "engineer"},
    {"name": "bob.b-2_", "hash": "$y$j9T$obvBnZVTKMr0wltDt0yiN.$Q6cuJ9xOxDlNeVTocFOfPGxxAs2Wlj.dOyts3v4cTrD"}]})";
  auto sut = UserFile::parse(text, "web-users.json");
  REQUIRE(sut);
  CHECK(sut->users().size() == 2);
  REQUIRE(sut->find("bob.b-2_") != nullptr);
  CHECK(sut->find("alice")->hash == SHA512_HASH);
  CHECK(sut->find("carol") == nullptr);
}

TEST_CASE("users file errors name the file and the place") {
  CHECK(parseError("{\"users\": [\n  {\"name\": }]}").starts_with("web-users.json:2:"));
  CHECK(parseError(R"({"people": []})").find("web-users.json: /people: unknown key") == 0);
  CHECK(parseError(R"({})") == "web-users.json: /users: missing (required)");
  const std::string hash = SHA512_HASH;
  CHECK(parseError(R"({"users": [{"name": "a", "hash": ")" + hash + R"("}, {"name": "a", "hash": ")" + hash +
                   "\"}]}") == "web-users.json: /users/1/name: user 'a' is given twice");
  CHECK(parseError(R"({"users": [{"name": "a b", "hash": ")" + hash + "\"}]}")
            .starts_with("web-users.json: /users/0/name: "));
  CHECK(parseError(R"({"users": [{"name": "a", "hash": "secret"}]})")
            .starts_with("web-users.json: /users/0/hash: not a crypt(3) hash"));
  CHECK(
      parseError(R"({"users": [{"name": "a", "hash": "$1$abc$def"}]})").starts_with("web-users.json: /users/0/hash: "));
  CHECK(parseError(R"({"users": [{"name": "a", "hash": "$6$IVxBmB2j5n6FtWJq$short"}]})") ==
        "web-users.json: /users/0/hash: not a complete SHA-512 hash");
  CHECK(parseError(R"({"users": [{"name": "a"}]})") == "web-users.json: /users/0/hash: missing (required)");
  CHECK(parseError(R"({"users": [{"name": "a", "hash": ")" + hash + R"(", "pasword": "x"}]})")
            .starts_with("web-users.json: /users/0/pasword: unknown key"));
}

TEST_CASE("loading a missing users file is an error naming it") {
  TempFolder folder;
  auto sut = UserFile::load(folder.file("absent.json"));
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().find("absent.json") != std::string::npos);
}

TEST_CASE("setPassword creates the users file with mode 0600 and replaces a password") {
  TempFolder folder;
  const std::string path = folder.file("web-users.json");
  REQUIRE(UserFile::setPassword(path, "alice", "first"));
  REQUIRE(UserFile::setPassword(path, "bob", "bobs"));
  struct stat info {};
  REQUIRE(::stat(path.c_str(), &info) == 0);
  CHECK((info.st_mode & 0777) == 0600);

  REQUIRE(UserFile::setPassword(path, "alice", "second"));
  auto sut = UserFile::load(path);
  REQUIRE(sut);
  CHECK(sut->users().size() == 2);
  REQUIRE(sut->find("alice") != nullptr);
  CHECK(verifyPassword("second", sut->find("alice")->hash));
  CHECK_FALSE(verifyPassword("first", sut->find("alice")->hash));
  REQUIRE(sut->find("bob") != nullptr);
  CHECK(verifyPassword("bobs", sut->find("bob")->hash));
}

TEST_CASE("setPassword through a symlink replaces the file it points to and keeps the link") {
  TempFolder folder;
  const std::string real = folder.file("real.json");
  const std::string link = folder.file("link.json");
  REQUIRE(UserFile::setPassword(real, "alice", "first"));
  std::filesystem::create_symlink("real.json", link);
  REQUIRE(UserFile::setPassword(link, "alice", "second"));
  CHECK(std::filesystem::is_symlink(link));
  auto sut = UserFile::load(real);
  REQUIRE(sut);
  REQUIRE(sut->find("alice") != nullptr);
  CHECK(verifyPassword("second", sut->find("alice")->hash));
}

TEST_CASE("setPassword leaves a broken users file untouched and refuses a bad name") {
  TempFolder folder;
  const std::string path = folder.file("web-users.json");
  { std::ofstream(path) << R"({"users": [{"name": "a", "hash": "plain"}]})"; }
  const Status sut = UserFile::setPassword(path, "alice", "pw");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().find("/users/0/hash") != std::string::npos);
  CHECK(readText(path) == R"({"users": [{"name": "a", "hash": "plain"}]})");
  CHECK_FALSE(UserFile::setPassword(folder.file("other.json"), "../x", "pw"));
  CHECK_FALSE(UserFile::setPassword(folder.file("other.json"), "alice", ""));
}

TEST_CASE("login gives a 64 hex digit token for the right password and refuses a wrong one") {
  const UserFile users = usersWithSha512();
  Sessions sut(60min);
  const auto now = Sessions::Clock::time_point{} + 1000s;
  Sessions::LoginRefusal refusal{};
  CHECK_FALSE(sut.login(users, "alice", "wrong", CLIENT, now, &refusal));
  CHECK(refusal == Sessions::LoginRefusal::WrongUserOrPassword);
  auto session = sut.login(users, "alice", SHA512_PASSWORD, CLIENT, now);
  REQUIRE(session);
  CHECK(session->user == "alice");
  CHECK(session->token.size() == 64);
  CHECK(session->token.find_first_not_of("0123456789abcdef") == std::string::npos);
  const Session* found = sut.find(session->token, now);
  REQUIRE(found != nullptr);
  CHECK(found->user == "alice");
  sut.logout(session->token);
  CHECK(sut.find(session->token, now) == nullptr);
}

TEST_CASE("an unknown user gets the answer of a wrong password after a full hash check") {
  const UserFile users = usersWithSha512();
  Sessions sut(60min);
  Sessions::LoginRefusal refusal{};
  const auto started = std::chrono::steady_clock::now();
  CHECK_FALSE(sut.login(users, "mallory", SHA512_PASSWORD, CLIENT, Sessions::Clock::time_point{}, &refusal));
  const auto took = std::chrono::steady_clock::now() - started;
  CHECK(refusal == Sessions::LoginRefusal::WrongUserOrPassword);
  // the dummy yescrypt hash costs what a real one does (tens of ms); a refused hash returns in microseconds
  CHECK(took >= 2ms);
}

TEST_CASE("a session expires after its lifetime without use") {
  const UserFile users = usersWithSha512();
  Sessions sut(60min);
  const auto start = Sessions::Clock::time_point{} + 1000s;
  auto session = sut.login(users, "alice", SHA512_PASSWORD, CLIENT, start);
  REQUIRE(session);
  CHECK(sut.find(session->token, start + 60min) == nullptr);
  CHECK(sut.size() == 0);
}

TEST_CASE("each use of a session pushes its expiry out") {
  const UserFile users = usersWithSha512();
  Sessions sut(60min);
  const auto start = Sessions::Clock::time_point{} + 1000s;
  auto session = sut.login(users, "alice", SHA512_PASSWORD, CLIENT, start);
  REQUIRE(session);
  CHECK(sut.find(session->token, start + 50min) != nullptr);
  CHECK(sut.find(session->token, start + 100min) != nullptr);
  CHECK(sut.find(session->token, start + 159min) != nullptr);
  CHECK(sut.find(session->token, start + 220min) == nullptr);
}

TEST_CASE("a login beyond maxSessions drops the session unused for longest") {
  const UserFile users = usersWithSha512();
  constexpr std::size_t MAX_SESSIONS = 2;
  Sessions sut(60min, MAX_SESSIONS);
  const auto start = Sessions::Clock::time_point{} + 1000s;
  auto first = sut.login(users, "alice", SHA512_PASSWORD, CLIENT, start);
  auto second = sut.login(users, "alice", SHA512_PASSWORD, CLIENT, start + 1s);
  REQUIRE(first);
  REQUIRE(second);
  REQUIRE(sut.find(first->token, start + 2s) != nullptr);  // now second is the least recently used
  auto third = sut.login(users, "alice", SHA512_PASSWORD, CLIENT, start + 3s);
  REQUIRE(third);
  CHECK(sut.size() == MAX_SESSIONS);
  CHECK(sut.find(second->token, start + 4s) == nullptr);
  CHECK(sut.find(first->token, start + 4s) != nullptr);
  CHECK(sut.find(third->token, start + 4s) != nullptr);
}

TEST_CASE("too many failed logins from one address are refused until the window has passed") {
  const UserFile users = usersWithSha512();
  constexpr int MAX_FAILURES = 3;
  Sessions sut(60min, 256, MAX_FAILURES, 60s);
  const auto start = Sessions::Clock::time_point{} + 1000s;
  for (int i = 0; i < MAX_FAILURES; ++i) {
    CHECK_FALSE(sut.login(users, "alice", "guess", CLIENT, start + std::chrono::seconds(10 * i)));
  }
  const auto afterThird = start + 20s;
  CHECK(sut.retryAfter(CLIENT, afterThird) == 40s);
  CHECK(sut.retryAfter("192.0.2.8", afterThird) == 0s);
  Sessions::LoginRefusal refusal{};
  CHECK_FALSE(sut.login(users, "alice", SHA512_PASSWORD, CLIENT, afterThird + 1s, &refusal));
  CHECK(refusal == Sessions::LoginRefusal::TooManyAttempts);
  CHECK(sut.login(users, "alice", SHA512_PASSWORD, "192.0.2.8", afterThird + 1s));
  CHECK(sut.retryAfter(CLIENT, start + 59s + 500ms) == 1s);  // rounded up
  CHECK(sut.retryAfter(CLIENT, start + 60s) == 0s);
  CHECK(sut.login(users, "alice", SHA512_PASSWORD, CLIENT, start + 60s));
  CHECK(sut.retryAfter(CLIENT, start + 60s) == 0s);  // a success forgets the failures
}

TEST_CASE("logins begun in parallel count against the limit before their check ends") {
  Sessions sut(60min, 256, 2, 60s);
  const auto now = Sessions::Clock::time_point{} + 1000s;
  CHECK(sut.beginLogin(CLIENT, now));
  CHECK(sut.beginLogin(CLIENT, now));
  CHECK_FALSE(sut.beginLogin(CLIENT, now));
  auto session = sut.completeLogin("alice", true, CLIENT, now);
  REQUIRE(session);
  CHECK(sut.beginLogin(CLIENT, now));
}

TEST_CASE("vcu-web passwd writes the password read from stdin") {
  TempFolder folder;
  const std::string path = folder.file("web-users.json");
  const std::string input = folder.file("password.txt");
  { std::ofstream(input) << "from stdin\n"; }
  const int savedStdin = ::dup(STDIN_FILENO);
  REQUIRE(std::freopen(input.c_str(), "r", stdin) != nullptr);
  std::cin.clear();
  std::array<std::string, 5> arguments{"vcu-web", "passwd", "--users", path, "alice"};
  std::array<char*, 5> argv{};
  for (std::size_t i = 0; i < arguments.size(); ++i) argv[i] = arguments[i].data();
  const int written = runPasswdCommand(static_cast<int>(argv.size()), argv.data());
  const int usage = runPasswdCommand(3, argv.data());  // no NAME
  ::dup2(savedStdin, STDIN_FILENO);
  ::close(savedStdin);
  std::cin.clear();
  CHECK(written == 0);
  CHECK(usage == 2);
  auto users = UserFile::load(path);
  REQUIRE(users);
  REQUIRE(users->find("alice") != nullptr);
  CHECK(verifyPassword("from stdin", users->find("alice")->hash));
}
