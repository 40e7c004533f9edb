// Conformance of openvcu::dbc against an independent decoder: for every DBC of the team
// kit's corpus (../shared/corpus/dbc, not copied into the repository) the canmatrix oracle
// (../shared/tools/dbc-oracle.py random --n 20 --seed 1939) writes 20 random payloads per
// message, each multiplexor value forced at least twice, with canmatrix's decode. openvcu
// must decode them to the same active signals, the same raw values (exactly), the same
// physical values (1e-9 relative, absolute near 0) and the same VAL_ text.
//
// Where canmatrix is wrong (corpus README "Where canmatrix itself is wrong", faults 1-7, and
// 8-9 found by this test) the difference is listed in canmatrix_faults.hpp with the fault's
// number; openvcu bugs, reported, are listed there too and shown as warnings. Any other
// difference fails, and so does a list entry that no longer explains any difference.
// Our rules where canmatrix differs: a 29-bit ID without the extended flag is extended;
// an ID with bit 29/30 is a pseudo message (never matched); VAL_ by raw value; of the
// signals that run outside the received bytes none is decoded, the others are.
//
// The vectors are generated on the first run and cached in the build tree by each DBC's
// sha1 (make_vectors.py); without the kit, /usr/bin/python3 or canmatrix the test says why
// and skips. A per-file report is written to <build>/tests/conformance/conformance-report.md
// (docs/conformance.md is made from it).

#include <doctest/doctest.h>

#include "skip.hpp"
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "canmatrix_faults.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/dbc/parser.hpp"

namespace {

namespace fs = std::filesystem;
namespace dbc = openvcu::dbc;
using nlohmann::json;
using openvcu::conformance::DiffKind;
using openvcu::conformance::KNOWN_CANMATRIX_FAULTS;
using openvcu::conformance::KNOWN_OPENVCU_BUGS;
using openvcu::conformance::KnownFault;

const fs::path CORPUS_DIR = OPENVCU_TEAM_KIT "/corpus/dbc";
const fs::path ORACLE = OPENVCU_TEAM_KIT "/tools/dbc-oracle.py";
const fs::path PYTHON = "/usr/bin/python3";  // the Debian interpreter that sees python3-canmatrix
const fs::path MAKE_VECTORS = OPENVCU_SOURCE_DIR "/tests/conformance/make_vectors.py";
const fs::path CACHE_DIR = OPENVCU_BINARY_DIR "/tests/conformance/vectors";
const fs::path REPORT = OPENVCU_BINARY_DIR "/tests/conformance/conformance-report.md";
constexpr int EXIT_SKIP = 77;  // make_vectors.py: canmatrix not importable
constexpr double RELATIVE_TOLERANCE = 1e-9;

// ------------------------------------------------------------------ vectors

struct CorpusFile {
  std::string name;  ///< path below corpus/dbc
  fs::path vectors;
  std::string oracleNote;  ///< what the oracle printed (skipped lines, decode errors)
};

struct Preparation {
  std::vector<CorpusFile> files;
  std::string skipReason;  ///< non-empty: the test cannot run here
  std::string failure;     ///< non-empty: the generator failed
};

std::string shellQuote(const std::string& text) {
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

Preparation prepareVectors() {
  Preparation out;
  if (!fs::is_directory(CORPUS_DIR) || !fs::is_regular_file(ORACLE)) {
    out.skipReason = "team kit not found (" + CORPUS_DIR.string() + ", " + ORACLE.string() + ")";
    return out;
  }
  if (!fs::exists(PYTHON)) {
    out.skipReason = PYTHON.string() + " not found (the oracle needs the Debian python3-canmatrix)";
    return out;
  }
  const std::string command = shellQuote(PYTHON) + " " + shellQuote(MAKE_VECTORS) + " --corpus " +
                              shellQuote(CORPUS_DIR) + " --oracle " + shellQuote(ORACLE) + " --cache " +
                              shellQuote(CACHE_DIR) + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    out.failure = "cannot run " + command;
    return out;
  }
  std::string output;
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe) != nullptr) output += buffer;
  const int status = pclose(pipe);
  const int exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (exitCode == EXIT_SKIP) {
    out.skipReason = output;
    return out;
  }
  if (exitCode != 0) {
    out.failure = command + " failed (" + std::to_string(exitCode) + "): " + output;
    return out;
  }
  std::ifstream index(CACHE_DIR / "index.tsv");
  std::string line;
  while (std::getline(index, line)) {
    std::istringstream fields(line);
    CorpusFile file;
    std::string sha1, vectors;
    std::getline(fields, file.name, '\t');
    std::getline(fields, sha1, '\t');
    std::getline(fields, vectors, '\t');
    std::getline(fields, file.oracleNote);
    file.vectors = vectors;
    out.files.push_back(std::move(file));
  }
  if (out.files.empty()) out.failure = "no vectors listed in " + (CACHE_DIR / "index.tsv").string();
  return out;
}

// ------------------------------------------------------------------ comparison

/// One kind of difference at one place, with how often it occurred and a first example.
struct Difference {
  std::string file, message, signal;
  DiffKind kind{};
  std::size_t count{};
  std::string example;
  const KnownFault* explainedBy{};  ///< a canmatrix fault, or an entry of KNOWN_OPENVCU_BUGS
  bool ourBug{};
};

/// What the test can verify about a difference, so that a list entry with a wildcard
/// explains only differences that really have the fault's cause.
struct Evidence {
  bool fault1Id{};          ///< our message: a 29-bit ID written without the extended flag
  bool fault1Follows{};     ///< the next BO_ in the file has such an ID (canmatrix moves its SG_ here)
  bool pseudo{};            ///< our message is a pseudo message and the matcher does not match it
  bool nonAscii{};          ///< the signal name or VAL_ text involved is not plain ASCII
  bool outsideFrame{};      ///< our signal of that name is not decodable or does not fit the data
  bool valUnterminated{};   ///< the signal's VAL_ line has no ';'
  bool valBeforeMessage{};  ///< the signal's VAL_ line comes before the message's BO_ line
};

/// Whether a fault's cause is present; nullopt when the test cannot tell. Checked for
/// entries with a wildcard; an entry naming message and signal was reviewed by hand.
std::optional<bool> premise(int fault, DiffKind kind, const Evidence& evidence) {
  if (fault == 1 && kind == DiffKind::MessageOnlyOurs) return evidence.fault1Id;
  if (fault == 1 && kind == DiffKind::SignalOnlyCanmatrix) return evidence.fault1Follows;
  if (fault == 2 && kind == DiffKind::Pseudo) return evidence.pseudo;
  if (fault == 4 && kind == DiffKind::SignalOnlyCanmatrix) return evidence.outsideFrame;
  if (fault == 7 && kind == DiffKind::Choice) return evidence.nonAscii || evidence.valUnterminated;
  if (fault == 7) return evidence.nonAscii;
  if (fault == 8 && kind == DiffKind::Choice) return evidence.valBeforeMessage;
  return std::nullopt;
}

/// Fault 1's trigger: an ID above 11 bits written without bit 31 (bits 29/30 masked, fault 2).
bool hasUnflaggedExtendedId(const dbc::Message& msg) {
  constexpr std::uint32_t EXTENDED_FLAG = 0x80000000u;
  constexpr std::uint32_t ID_29_BITS = 0x1FFFFFFFu;
  constexpr std::uint32_t MAX_STANDARD_ID = 0x7FFu;
  return (msg.declaredId & EXTENDED_FLAG) == 0 && (msg.declaredId & ID_29_BITS) > MAX_STANDARD_ID;
}

bool isAscii(std::string_view text) {
  return std::all_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) < 0x80; });
}

struct FileTally {
  std::string name;
  std::string oracleNote;
  std::size_t parseErrors{};
  std::size_t vectors{};           ///< compared
  std::size_t vectorsWithError{};  ///< skipped: canmatrix reported an error
  std::size_t signalsCompared{};
  std::size_t signalsAgree{};
  std::size_t signalsDiffer{};
  std::size_t messageDifferences{};    ///< message-level (ID, pseudo, missing) occurrences
  std::map<int, std::size_t> byFault;  ///< fault number -> signal + message differences
  std::size_t ourBugs{};               ///< differences on KNOWN_OPENVCU_BUGS
  std::size_t unexplained{};
  std::set<std::string> oracleErrors;  ///< canmatrix's decode errors (vectors skipped)
};

struct Run {
  std::vector<FileTally> files;
  std::vector<Difference> differences;
};

std::string numberText(const json& value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

std::string rawText(const dbc::DecodedValue& value) {
  std::ostringstream text;
  text.precision(17);
  switch (value.kind) {
    case dbc::RawKind::Unsigned:
      text << value.rawUnsigned;
      break;
    case dbc::RawKind::Signed:
      text << value.rawSigned;
      break;
    default:
      text << value.rawFloat;
      break;
  }
  return text.str();
}

/// A JSON number as the oracle writes it ("nan", "inf", "-inf" as strings).
double asDouble(const json& value) {
  if (value.is_string()) {
    const auto text = value.get<std::string>();
    if (text == "nan") return std::nan("");
    if (text == "inf") return INFINITY;
    if (text == "-inf") return -INFINITY;
    return std::nan("");
  }
  if (value.is_number_unsigned()) return static_cast<double>(value.get<std::uint64_t>());
  if (value.is_number_integer()) return static_cast<double>(value.get<std::int64_t>());
  if (value.is_number()) return value.get<double>();
  return std::nan("");
}

bool sameDouble(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::fabs(a - b) <= RELATIVE_TOLERANCE * std::max({1.0, std::fabs(a), std::fabs(b)});
}

bool sameRaw(const json& theirs, const dbc::DecodedValue& ours) {
  const bool integer = ours.kind == dbc::RawKind::Unsigned || ours.kind == dbc::RawKind::Signed;
  if (integer && theirs.is_number_unsigned()) {
    const auto value = theirs.get<std::uint64_t>();
    return ours.kind == dbc::RawKind::Unsigned
               ? ours.rawUnsigned == value
               : ours.rawSigned >= 0 && static_cast<std::uint64_t>(ours.rawSigned) == value;
  }
  if (integer && theirs.is_number_integer()) {
    return ours.kind == dbc::RawKind::Signed && ours.rawSigned == theirs.get<std::int64_t>();
  }
  const double mine = ours.kind == dbc::RawKind::Unsigned ? static_cast<double>(ours.rawUnsigned)
                      : ours.kind == dbc::RawKind::Signed ? static_cast<double>(ours.rawSigned)
                                                          : ours.rawFloat;
  const double other = asDouble(theirs);
  if (std::isnan(mine) || std::isnan(other)) return std::isnan(mine) && std::isnan(other);
  return mine == other;  // exactly
}

std::vector<std::uint8_t> bytesOf(const std::string& hex) {
  std::vector<std::uint8_t> bytes;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) {
    bytes.push_back(static_cast<std::uint8_t>(std::stoul(hex.substr(i, 2), nullptr, 16)));
  }
  return bytes;
}

class FileComparison {
 public:
  FileComparison(const CorpusFile& file, Run& run) : m_file(file), m_run(run) { m_tally.name = file.name; }

  void compare() {
    m_tally.oracleNote = m_file.oracleNote;
    std::ifstream dbcStream(CORPUS_DIR / m_file.name, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(dbcStream)), std::istreambuf_iterator<char>());
    indexValueDescriptions(text);
    dbc::ParseOutput parsed = dbc::parse(text, m_file.name);
    m_tally.parseErrors = parsed.errorCount();
    m_db = std::move(parsed.database);
    for (std::size_t i = 0; i < m_db.messages.size(); ++i) {
      m_byDisplayName.emplace(m_db.messages[i].displayName, i);
      m_byName.emplace(m_db.messages[i].name, i);
    }
    m_matcher = dbc::MessageMatcher(m_db, dbc::MatchMode::J1939);
    m_codecs.resize(m_db.messages.size());
    m_seen.assign(m_db.messages.size(), false);

    std::ifstream vectors(m_file.vectors);
    std::string line;
    while (std::getline(vectors, line)) {
      if (!line.empty()) compareVector(json::parse(line));
    }
    for (std::size_t i = 0; i < m_db.messages.size(); ++i) {
      const dbc::Message& msg = m_db.messages[i];
      if (m_seen[i] || msg.pseudo) continue;
      addMessageDifference(msg, msg.displayName, DiffKind::MessageOnlyOurs, "canmatrix has no frame " + msg.name);
    }
    m_run.files.push_back(m_tally);
  }

 private:
  /// The message a vector names: canmatrix names it by SystemMessageLongSymbol when set;
  /// among equal names the one with the vector's ID.
  const dbc::Message* findMessage(const std::string& name, std::uint32_t id, bool extended) const {
    const dbc::Message* first = nullptr;
    for (const auto* index : {&m_byDisplayName, &m_byName}) {
      const auto [begin, end] = index->equal_range(name);
      for (auto it = begin; it != end; ++it) {
        const dbc::Message& msg = m_db.messages[it->second];
        if (msg.id == id && msg.extended == extended) return &msg;
        if (first == nullptr) first = &msg;
      }
    }
    return first;
  }

  /// Where each "VAL_ <id> <signal>" line is and whether it ends with ';' (for faults 7, 8).
  void indexValueDescriptions(const std::string& text) {
    std::istringstream lines(text);
    std::string line;
    for (std::uint32_t number = 1; std::getline(lines, line); ++number) {
      std::istringstream words(line);
      std::string keyword, id, signal;
      words >> keyword >> id >> signal;
      if (keyword != "VAL_") continue;
      m_valLines.emplace(id + ' ' + signal, std::make_pair(number, line.find(';') != std::string::npos));
    }
  }

  std::size_t indexOf(const dbc::Message& msg) const { return static_cast<std::size_t>(&msg - m_db.messages.data()); }

  const dbc::MessageCodec& codecOf(const dbc::Message& msg) {
    std::optional<dbc::MessageCodec>& codec = m_codecs[indexOf(msg)];
    if (!codec) codec = dbc::MessageCodec::compile(m_db, msg);
    return *codec;
  }

  Evidence messageEvidence(const dbc::Message& msg) const {
    Evidence evidence;
    evidence.fault1Id = hasUnflaggedExtendedId(msg);
    const std::size_t next = indexOf(msg) + 1;
    evidence.fault1Follows = next < m_db.messages.size() && hasUnflaggedExtendedId(m_db.messages[next]);
    return evidence;
  }

  /// Our signal of a (display) name does not fit `length` bytes or is not decodable.
  bool outsideFrame(const dbc::Message& msg, const std::string& name, std::size_t length) {
    for (std::uint32_t i = 0; i < msg.signals.size(); ++i) {
      if (msg.signals[i].displayName != name) continue;
      const dbc::CompiledSignal* compiled = codecOf(msg).find(i);
      return compiled == nullptr || compiled->lastByte >= length;
    }
    return false;
  }

  void compareVector(const json& vector) {
    const std::string messageName = vector.at("msg");
    const auto id = vector.at("id").get<std::uint32_t>();
    const bool extended = vector.at("ext").get<bool>();
    const dbc::Message* msg = findMessage(messageName, id, extended);
    if (msg != nullptr) m_seen[indexOf(*msg)] = true;
    if (vector.contains("error")) {
      ++m_tally.vectorsWithError;
      m_tally.oracleErrors.insert(vector.at("error").get<std::string>().substr(0, 80));
      return;
    }
    ++m_tally.vectors;
    const std::string data = vector.at("data");
    if (msg == nullptr) {
      ++m_tally.messageDifferences;
      add(messageName, "", DiffKind::MessageMissing, "data " + data, Evidence{});
      return;
    }
    if (msg->pseudo) {
      Evidence evidence = messageEvidence(*msg);
      evidence.pseudo = m_matcher.match(id, extended) != static_cast<std::int32_t>(indexOf(*msg));
      ++m_tally.messageDifferences;
      add(messageName, "", DiffKind::Pseudo,
          "declared " + std::to_string(msg->declaredId) + ", canmatrix frame id " + std::to_string(id) +
              (extended ? " ext" : " std"),
          evidence);
    } else if (msg->id != id || msg->extended != extended) {
      addMessageDifference(*msg, messageName, DiffKind::Id,
                           "ours " + std::to_string(msg->id) + (msg->extended ? " ext" : " std") + ", canmatrix " +
                               std::to_string(id) + (extended ? " ext" : " std"));
    }

    // Ours: display name -> (signal, value) for every active signal that fits the data.
    std::map<std::string, std::pair<const dbc::Signal*, dbc::DecodedValue>> ours;
    const std::vector<std::uint8_t> payload = bytesOf(data);
    codecOf(*msg).decode(payload, [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
      const dbc::Signal& sig = msg->signals[signalIndex];
      ours.emplace(sig.displayName, std::make_pair(&sig, value));
    });

    const json& signals = vector.at("signals");
    const json& raw = vector.at("raw");
    const json choices = vector.value("choices", json::object());
    std::set<std::string> names;
    for (const auto& [name, value] : signals.items()) names.insert(name);
    for (const auto& [name, value] : ours) names.insert(name);

    const Evidence onMessage = messageEvidence(*msg);
    for (const std::string& name : names) {
      ++m_tally.signalsCompared;
      Evidence evidence = onMessage;
      evidence.nonAscii = !isAscii(name);
      const std::string where = "data " + data + ": ";
      const auto mine = ours.find(name);
      if (mine == ours.end()) {
        evidence.outsideFrame = outsideFrame(*msg, name, payload.size());
        addSignalDifference(messageName, name, DiffKind::SignalOnlyCanmatrix,
                            where + "canmatrix raw " + numberText(raw.at(name)), evidence);
        continue;
      }
      const auto& [sig, value] = mine->second;
      if (!signals.contains(name)) {
        addSignalDifference(messageName, name, DiffKind::SignalOnlyOurs, where + "ours raw " + rawText(value),
                            evidence);
        continue;
      }
      if (!sameRaw(raw.at(name), value)) {
        addSignalDifference(messageName, name, DiffKind::Raw,
                            where + "ours " + rawText(value) + ", canmatrix " + numberText(raw.at(name)), evidence);
        continue;
      }
      if (!sameDouble(value.physical, asDouble(signals.at(name)))) {
        std::ostringstream detail;
        detail.precision(17);
        detail << where << "ours " << value.physical << ", canmatrix " << numberText(signals.at(name));
        addSignalDifference(messageName, name, DiffKind::Physical, detail.str(), evidence);
        continue;
      }
      // VAL_ by raw value (DBC's meaning; the oracle's "choices" uses raw keys too).
      const std::string* label = nullptr;
      if (value.kind == dbc::RawKind::Unsigned || value.kind == dbc::RawKind::Signed) {
        label = sig->describe(value.kind == dbc::RawKind::Signed ? value.rawSigned
                                                                 : static_cast<std::int64_t>(value.rawUnsigned));
      }
      const bool theyLabel = choices.contains(name);
      const std::string theirLabel = theyLabel ? choices.at(name).get<std::string>() : std::string();
      if ((label != nullptr) != theyLabel || (label != nullptr && *label != theirLabel)) {
        evidence.nonAscii = evidence.nonAscii || !isAscii(theirLabel) || (label != nullptr && !isAscii(*label));
        if (const auto it = m_valLines.find(std::to_string(msg->declaredId) + ' ' + sig->name);
            it != m_valLines.end()) {
          evidence.valUnterminated = !it->second.second;
          evidence.valBeforeMessage = it->second.first < msg->source.line;
        }
        addSignalDifference(messageName, name, DiffKind::Choice,
                            where + "ours '" + (label ? *label : std::string("<none>")) + "', canmatrix '" +
                                (theyLabel ? theirLabel : std::string("<none>")) + "'",
                            evidence);
        continue;
      }
      ++m_tally.signalsAgree;
    }
  }

  void addSignalDifference(const std::string& message, const std::string& signal, DiffKind kind,
                           const std::string& example, const Evidence& evidence) {
    ++m_tally.signalsDiffer;
    add(message, signal, kind, example, evidence);
  }

  void addMessageDifference(const dbc::Message& msg, const std::string& message, DiffKind kind,
                            const std::string& example) {
    ++m_tally.messageDifferences;
    add(message, "", kind, example, messageEvidence(msg));
  }

  void add(const std::string& message, const std::string& signal, DiffKind kind, const std::string& example,
           const Evidence& evidence) {
    bool ourBug = false;
    const KnownFault* entry = explain(KNOWN_CANMATRIX_FAULTS, message, signal, kind, evidence);
    if (entry == nullptr) {
      entry = explain(KNOWN_OPENVCU_BUGS, message, signal, kind, evidence);
      ourBug = entry != nullptr;
    }
    if (ourBug) {
      ++m_tally.ourBugs;
    } else if (entry != nullptr) {
      ++m_tally.byFault[entry->fault];
    } else {
      ++m_tally.unexplained;
    }
    const std::string key = message + '\x1f' + signal + '\x1f' + std::string(toString(kind)) + '\x1f' +
                            std::to_string(reinterpret_cast<std::uintptr_t>(entry));
    const auto [it, inserted] = m_index.emplace(key, m_run.differences.size());
    if (inserted)
      m_run.differences.push_back(Difference{m_file.name, message, signal, kind, 0, example, entry, ourBug});
    ++m_run.differences[it->second].count;
  }

  template <std::size_t N>
  const KnownFault* explain(const std::array<KnownFault, N>& list, const std::string& message,
                            const std::string& signal, DiffKind kind, const Evidence& evidence) const {
    for (const KnownFault& entry : list) {
      if (entry.file != m_file.name || entry.kind != kind) continue;
      if (entry.message != "*" && entry.message != message) continue;
      if (entry.signal != "*" && entry.signal != signal) continue;
      const bool wildcard = entry.message == "*" || entry.signal == "*";
      if (!wildcard) return &entry;  // reviewed one by one
      const std::optional<bool> causePresent = premise(entry.fault, kind, evidence);
      if (causePresent.value_or(false)) return &entry;
    }
    return nullptr;
  }

  const CorpusFile& m_file;
  Run& m_run;
  FileTally m_tally;
  dbc::Database m_db;
  std::unordered_multimap<std::string, std::size_t> m_byDisplayName;
  std::unordered_multimap<std::string, std::size_t> m_byName;
  dbc::MessageMatcher m_matcher;
  std::vector<std::optional<dbc::MessageCodec>> m_codecs;
  std::vector<bool> m_seen;
  std::unordered_map<std::string, std::size_t> m_index;  ///< into m_run.differences, this file only
  std::unordered_map<std::string, std::pair<std::uint32_t, bool>> m_valLines;  ///< "id signal" -> (line, has ';')
};

std::string faultsText(const std::map<int, std::size_t>& byFault) {
  std::ostringstream text;
  for (const auto& [fault, count] : byFault) {
    if (text.tellp() > 0) text << ", ";
    text << '#' << fault << ": " << count;
  }
  return text.tellp() > 0 ? text.str() : std::string("-");
}

std::string cell(std::string text) {
  for (std::size_t at = 0; (at = text.find('|', at)) != std::string::npos; at += 2) text.replace(at, 1, "\\|");
  return text;
}

/// The oracle's stderr line without the path it starts with ("# /path/x.dbc: loader ...").
std::string oracleNote(const std::string& note) {
  const std::size_t colon = note.find(".dbc: ");
  const std::size_t colonUpper = note.find(".DBC: ");
  const std::size_t at = std::min(colon, colonUpper);
  return at == std::string::npos ? note : note.substr(at + 6);
}

void writeReport(const Run& run) {
  std::ofstream out(REPORT);
  FileTally total;
  out << "| file | vectors | skipped (canmatrix error) | signals compared | agree | differ | "
         "message-level differences | explained by canmatrix fault | openvcu bug | unexplained |\n"
         "|---|---:|---:|---:|---:|---:|---:|---|---:|---:|\n";
  for (const FileTally& file : run.files) {
    out << "| " << file.name << " | " << file.vectors << " | " << file.vectorsWithError << " | " << file.signalsCompared
        << " | " << file.signalsAgree << " | " << file.signalsDiffer << " | " << file.messageDifferences << " | "
        << faultsText(file.byFault) << " | " << file.ourBugs << " | " << file.unexplained << " |\n";
    total.vectors += file.vectors;
    total.vectorsWithError += file.vectorsWithError;
    total.signalsCompared += file.signalsCompared;
    total.signalsAgree += file.signalsAgree;
    total.signalsDiffer += file.signalsDiffer;
    total.messageDifferences += file.messageDifferences;
    total.ourBugs += file.ourBugs;
    total.unexplained += file.unexplained;
    for (const auto& [fault, count] : file.byFault) total.byFault[fault] += count;
  }
  out << "| **total (" << run.files.size() << " files)** | " << total.vectors << " | " << total.vectorsWithError
      << " | " << total.signalsCompared << " | " << total.signalsAgree << " | " << total.signalsDiffer << " | "
      << total.messageDifferences << " | " << faultsText(total.byFault) << " | " << total.ourBugs << " | "
      << total.unexplained << " |\n\n";

  out << "Oracle notes (canmatrix loader and decode errors) and openvcu parse errors:\n\n";
  for (const FileTally& file : run.files) {
    if (file.oracleNote.empty() && file.parseErrors == 0 && file.oracleErrors.empty()) continue;
    out << "- " << file.name << ": " << oracleNote(file.oracleNote);
    for (const std::string& error : file.oracleErrors) out << " [" << error << "]";
    if (file.parseErrors > 0) out << " (openvcu: " << file.parseErrors << " parse errors)";
    out << "\n";
  }
  out << "\n| file | message | signal | kind | count | explained by | example |\n|---|---|---|---|---:|---|---|\n";
  for (const Difference& diff : run.differences) {
    std::string by = "**unexplained**";
    if (diff.ourBug) {
      by = "**openvcu bug**";
    } else if (diff.explainedBy != nullptr) {
      by = "canmatrix #" + std::to_string(diff.explainedBy->fault);
    }
    out << "| " << diff.file << " | " << cell(diff.message) << " | " << cell(diff.signal) << " | "
        << toString(diff.kind) << " | " << diff.count << " | " << by << " | " << cell(diff.example) << " |\n";
  }
}

/// The comparison, done once per process (both test cases use it).
const Run& conformanceRun(const Preparation& preparation) {
  static const Run run = [&] {
    Run result;
    for (const CorpusFile& file : preparation.files) FileComparison(file, result).compare();
    writeReport(result);
    return result;
  }();
  return run;
}

const Preparation& preparation() {
  static const Preparation prepared = prepareVectors();
  return prepared;
}

std::string describe(const Difference& diff) {
  std::ostringstream text;
  text << diff.file << " message '" << diff.message << "' signal '" << diff.signal << "' " << toString(diff.kind)
       << " x" << diff.count << " (" << diff.example << ")";
  return text.str();
}

template <std::size_t N>
void checkEveryEntryIsUsed(const Run& run, const std::array<KnownFault, N>& list) {
  for (const KnownFault& entry : list) {
    const bool used = std::any_of(run.differences.begin(), run.differences.end(),
                                  [&](const Difference& diff) { return diff.explainedBy == &entry; });
    CHECK_MESSAGE(used, "stale entry: " << entry.file << " message '" << entry.message << "' signal '" << entry.signal
                                        << "' " << toString(entry.kind) << " (#" << entry.fault << ": " << entry.reason
                                        << ")");
  }
}

}  // namespace

TEST_CASE("every corpus DBC decodes the canmatrix vectors alike, apart from listed canmatrix faults") {
  const Preparation& prepared = preparation();
  if (!prepared.skipReason.empty()) {
    OPENVCU_SKIP("skipped: " << prepared.skipReason);
  }
  REQUIRE_MESSAGE(prepared.failure.empty(), prepared.failure);

  const Run& sut = conformanceRun(prepared);

  std::size_t compared = 0;
  std::size_t agree = 0;
  for (const FileTally& file : sut.files) {
    compared += file.signalsCompared;
    agree += file.signalsAgree;
  }
  MESSAGE(sut.files.size() << " DBC files, " << compared << " signal values compared, " << agree
                           << " agree; report: " << REPORT.string());
  CHECK(compared > 0);
  for (const Difference& diff : sut.differences) {
    if (diff.ourBug) {
      WARN_MESSAGE(false, "known openvcu bug (" << diff.explainedBy->reason << "): " << describe(diff));
      continue;
    }
    CHECK_MESSAGE(diff.explainedBy != nullptr, "not a listed canmatrix fault: " << describe(diff));
  }
}

TEST_CASE("every entry of the canmatrix fault and openvcu bug lists still explains a difference") {
  const Preparation& prepared = preparation();
  if (!prepared.skipReason.empty()) {
    OPENVCU_SKIP("skipped: " << prepared.skipReason);
  }
  REQUIRE_MESSAGE(prepared.failure.empty(), prepared.failure);

  const Run& sut = conformanceRun(prepared);

  checkEveryEntryIsUsed(sut, KNOWN_CANMATRIX_FAULTS);
  checkEveryEntryIsUsed(sut, KNOWN_OPENVCU_BUGS);
}
