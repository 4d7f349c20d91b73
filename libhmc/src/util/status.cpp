// SPDX-License-Identifier: AGPL-3.0-or-later
#include "hmc/status.hpp"

namespace hmc {

const char* status_name(Status s) noexcept {
  switch (s) {
    case Status::ok: return "ok";
    case Status::bad_magic: return "bad_magic";
    case Status::unsupported_version: return "unsupported_version";
    case Status::crc_mismatch: return "crc_mismatch";
    case Status::truncated: return "truncated";
    case Status::bad_chunk: return "bad_chunk";
    case Status::bad_header: return "bad_header";
    case Status::bad_huffman_table: return "bad_huffman_table";
    case Status::bad_layer: return "bad_layer";
    case Status::limit_exceeded: return "limit_exceeded";
    case Status::invalid_argument: return "invalid_argument";
    case Status::io_error: return "io_error";
    case Status::parse_error: return "parse_error";
    case Status::unsupported_format: return "unsupported_format";
    case Status::out_of_memory: return "out_of_memory";
    case Status::internal_error: return "internal_error";
  }
  return "unknown_status";
}

const char* status_description(Status s) noexcept {
  switch (s) {
    case Status::ok: return "success";
    case Status::bad_magic: return "not an HMC stream (wrong signature)";
    case Status::unsupported_version: return "HMC stream of an unsupported major version";
    case Status::crc_mismatch: return "a chunk's CRC-32 does not match (corrupted stream)";
    case Status::truncated: return "the stream ends before a complete level";
    case Status::bad_chunk: return "invalid chunk length, order, count or type";
    case Status::bad_header: return "a header or quantizer field is out of range";
    case Status::bad_huffman_table: return "invalid Huffman code-length table";
    case Status::bad_layer: return "malformed vertex layer or side information";
    case Status::limit_exceeded: return "the stream exceeds the decoder's limits";
    case Status::invalid_argument: return "invalid argument";
    case Status::io_error: return "file input/output failed";
    case Status::parse_error: return "malformed input file";
    case Status::unsupported_format: return "unsupported file format";
    case Status::out_of_memory: return "out of memory";
    case Status::internal_error: return "internal error in libhmc";
  }
  return "unknown status";
}

std::string Error::to_string() const {
  std::string s = status_name(status);
  if (!message.empty()) {
    s += ": ";
    s += message;
  }
  return s;
}

}  // namespace hmc
