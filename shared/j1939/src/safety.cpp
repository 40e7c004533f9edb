#include "openvcu/j1939/safety.hpp"

namespace openvcu::j1939 {
namespace {

constexpr std::uint32_t CRC_POLYNOMIAL = 0x6938392Du;
constexpr std::uint32_t CRC_INITIAL = 0xFFFFFFFFu;
constexpr std::uint32_t CRC_TOP_BIT = 0x80000000u;
constexpr std::uint8_t SEQUENCE_SHIFT = 3;
constexpr std::uint8_t RESERVED_BIT = 1u << 2;
constexpr std::uint8_t INVERTED_EDP_BIT = 1u << 1;
constexpr std::uint8_t INVERTED_DP_BIT = 1u << 0;
constexpr std::size_t CRC_OFFSET = 4;

using CrcTable = std::array<std::uint32_t, 256>;

// One table entry per leading byte: the CRC register after shifting that byte through
// eight steps of the non-reflected division. Built at compile time.
constexpr CrcTable makeCrcTable() noexcept {
  CrcTable table{};
  for (std::uint32_t byte = 0; byte < table.size(); ++byte) {
    std::uint32_t reg = byte << 24;
    for (int bit = 0; bit < 8; ++bit) {
      reg = (reg & CRC_TOP_BIT) != 0 ? (reg << 1) ^ CRC_POLYNOMIAL : reg << 1;
    }
    table[byte] = reg;
  }
  return table;
}

constexpr CrcTable CRC_TABLE = makeCrcTable();

constexpr std::uint32_t crcOf(std::span<const std::uint8_t> data) noexcept {
  std::uint32_t reg = CRC_INITIAL;
  for (const std::uint8_t byte : data) {
    reg = (reg << 8) ^ CRC_TABLE[((reg >> 24) ^ byte) & 0xFFu];
  }
  return reg;
}

constexpr std::array<std::uint8_t, 8> THESIS_SDM{0xEF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
static_assert(crcOf(THESIS_SDM) == 0x8100EFA3u, "J1939-76 CRC known answer (thesis Figure 6.13)");

constexpr std::uint8_t inverted(std::uint8_t value) noexcept {
  return static_cast<std::uint8_t>(~value);
}

}  // namespace

std::uint32_t crc32J1939_76(std::span<const std::uint8_t> data) noexcept { return crcOf(data); }

SafetyPayload buildSafetyHeader(std::uint32_t dataCanId, SafetyDataView data,
                                std::uint8_t sequence) noexcept {
  assert(sequence < SAFETY_SEQUENCE_MODULO);
  const Id sdm = Id::fromCanId(dataCanId);
  const std::uint32_t crc = crcOf(data);
  std::uint8_t first =
      static_cast<std::uint8_t>((sequence % SAFETY_SEQUENCE_MODULO) << SEQUENCE_SHIFT);
  first |= RESERVED_BIT;
  if (!sdm.extendedDataPage) first |= INVERTED_EDP_BIT;
  if (!sdm.dataPage) first |= INVERTED_DP_BIT;
  return SafetyPayload{first,
                       inverted(sdm.sourceAddress),
                       inverted(sdm.pduSpecific),
                       inverted(sdm.pduFormat),
                       static_cast<std::uint8_t>(crc & 0xFFu),
                       static_cast<std::uint8_t>((crc >> 8) & 0xFFu),
                       static_cast<std::uint8_t>((crc >> 16) & 0xFFu),
                       static_cast<std::uint8_t>((crc >> 24) & 0xFFu)};
}

std::optional<SafetyHeader> parseSafetyHeader(std::span<const std::uint8_t> headerData) noexcept {
  if (headerData.size() != SAFETY_MESSAGE_LENGTH) return std::nullopt;
  SafetyHeader header;
  header.sequence = static_cast<std::uint8_t>(headerData[0] >> SEQUENCE_SHIFT);
  header.sdmExtendedDataPage = (headerData[0] & INVERTED_EDP_BIT) == 0;
  header.sdmDataPage = (headerData[0] & INVERTED_DP_BIT) == 0;
  header.sdmSourceAddress = inverted(headerData[1]);
  header.sdmPduSpecific = inverted(headerData[2]);
  header.sdmPduFormat = inverted(headerData[3]);
  header.sdmCrc = static_cast<std::uint32_t>(headerData[CRC_OFFSET]) |
                  (static_cast<std::uint32_t>(headerData[CRC_OFFSET + 1]) << 8) |
                  (static_cast<std::uint32_t>(headerData[CRC_OFFSET + 2]) << 16) |
                  (static_cast<std::uint32_t>(headerData[CRC_OFFSET + 3]) << 24);
  return header;
}

std::string_view safetyResultName(SafetyResult result) noexcept {
  switch (result) {
    case SafetyResult::Ok: return "Ok";
    case SafetyResult::Synchronising: return "Synchronising";
    case SafetyResult::MissingHeader: return "MissingHeader";
    case SafetyResult::BadLength: return "BadLength";
    case SafetyResult::Timeout: return "Timeout";
    case SafetyResult::CycleTimeout: return "CycleTimeout";
    case SafetyResult::HeaderMismatch: return "HeaderMismatch";
    case SafetyResult::CrcMismatch: return "CrcMismatch";
    case SafetyResult::Repetition: return "Repetition";
    case SafetyResult::SequenceError: return "SequenceError";
  }
  return "Unknown";
}

SafetyPairChecker::SafetyPairChecker(const SafetyPairConfig& config) noexcept
    : m_config(config), m_headerCanId(safetyHeaderCanId(config.dataCanId)) {
  assert(config.maxHeaderToDataNs > 0);
  assert(config.maxHeaderCycleNs > 0);
}

void SafetyPairChecker::onHeader(std::span<const std::uint8_t> headerData,
                                 std::int64_t timestampNs) noexcept {
  if (m_hasPendingHeader) ++m_droppedHeaders;
  m_hasPendingHeader = true;
  m_pendingHeaderNs = timestampNs;
  m_pendingCycleLate = m_hasLastHeader && timestampNs - m_lastHeaderNs > m_config.maxHeaderCycleNs;
  m_pendingLengthOk = headerData.size() == SAFETY_MESSAGE_LENGTH;
  if (m_pendingLengthOk) {
    for (std::size_t i = 0; i < SAFETY_MESSAGE_LENGTH; ++i) m_pendingHeader[i] = headerData[i];
  }
  m_hasLastHeader = true;
  m_lastHeaderNs = timestampNs;
}

SafetyResult SafetyPairChecker::onData(std::span<const std::uint8_t> data,
                                       std::int64_t timestampNs) noexcept {
  const SafetyResult result = check(data, timestampNs);
  ++m_counts[static_cast<std::size_t>(result)];
  if (result != SafetyResult::Ok && result != SafetyResult::Synchronising) m_hasReference = false;
  return result;
}

SafetyResult SafetyPairChecker::check(std::span<const std::uint8_t> data,
                                      std::int64_t timestampNs) noexcept {
  if (!m_hasPendingHeader || timestampNs < m_pendingHeaderNs) return SafetyResult::MissingHeader;
  m_hasPendingHeader = false;  // one SHM guards one SDM
  if (!m_pendingLengthOk || data.size() != SAFETY_MESSAGE_LENGTH) return SafetyResult::BadLength;
  if (timestampNs - m_pendingHeaderNs > m_config.maxHeaderToDataNs) return SafetyResult::Timeout;
  if (m_pendingCycleLate) return SafetyResult::CycleTimeout;

  const std::optional<SafetyHeader> maybeHeader = parseSafetyHeader(m_pendingHeader);
  if (!maybeHeader || !maybeHeader->matchesData(m_config.dataCanId)) {
    return SafetyResult::HeaderMismatch;
  }
  if (maybeHeader->sdmCrc != crcOf(data)) return SafetyResult::CrcMismatch;

  const std::uint8_t sequence = maybeHeader->sequence;
  if (!m_hasReference) {
    m_hasReference = true;
    m_reference = sequence;
    return SafetyResult::Synchronising;
  }
  if (sequence == m_reference) return SafetyResult::Repetition;
  if (sequence != (m_reference + 1u) % SAFETY_SEQUENCE_MODULO) return SafetyResult::SequenceError;
  m_reference = sequence;
  return SafetyResult::Ok;
}

bool SafetyPairChecker::headerOverdue(std::int64_t nowNs) const noexcept {
  return !m_hasLastHeader || nowNs - m_lastHeaderNs > m_config.maxHeaderCycleNs;
}

void SafetyPairChecker::reset() noexcept {
  m_hasPendingHeader = false;
  m_pendingLengthOk = false;
  m_pendingCycleLate = false;
  m_hasLastHeader = false;
  m_hasReference = false;
}

}  // namespace openvcu::j1939
