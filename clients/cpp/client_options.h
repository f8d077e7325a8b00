// client_options.h: how a MapClient connects and calls: bearer token, TLS, deadline, batching.
// Units: seconds, items. Threads: a plain value.
#pragma once

#include <cstddef>
#include <string>

namespace cenote::client {

struct ClientOptions {
  // Sent as `authorization: Bearer <token>` on every call; empty: no authorization metadata.
  std::string token;
  // TLS: PEM root certificate(s) the server's certificate must chain to. Empty with use_tls: the
  // system's roots. use_tls false: plaintext (the server's default, on loopback).
  bool use_tls = false;
  std::string tls_root_cert_pem;
  // Mutual TLS: this client's certificate chain and private key (PEM); both or neither.
  std::string tls_client_cert_pem;
  std::string tls_client_key_pem;
  // Every unary call fails with DEADLINE_EXCEEDED after this long; <= 0: no deadline.
  double deadline_s = 10.0;
  // Queries with more items than this are split into several requests of at most this many
  // (the server's `server.max_batch`, 100000 by default); 0: never split (the server decides).
  size_t max_batch_items = 100000;
  // Largest message sent or received, bytes (the server's `server.max_message_bytes`).
  int max_message_bytes = 64 * 1024 * 1024;
  // A channel of its own (its own TCP connection) rather than one shared with other clients of
  // the same target in this process: for load generators that want N connections.
  bool own_connection = false;
};

}  // namespace cenote::client
