// The viewer's networking, Boost.Beast over Boost.Asio (the only file that includes them): HTTP
// for the page's files, the WebSocket upgrade with its token and subprotocol checks, and one
// session per client that queues what the feed (viewer_feed.h) sends it.
#include "server/viewer/viewer_server.h"

#include <utility>  // before Asio: its awaitable.hpp uses std::exchange

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <chrono>
#include <deque>
#include <filesystem>
#include <fstream>
#include <future>
#include <sstream>

#include "common/error.h"
#include "common/thread_name.h"
#include "server/viewer/viewer_feed.h"

#ifndef CENOTE_WEB_DIR
#define CENOTE_WEB_DIR ""
#endif

namespace cenote::server::viewer {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
namespace fs = std::filesystem;

constexpr size_t kMaxClientMessageBytes = 64 * 1024;  // subscribe / unsubscribe are a few hundred bytes
constexpr size_t kMaxRequestHeaderBytes = 16 * 1024;

bool equalConstantTime(const std::string& given, const std::string& token) {
  if (given.size() != token.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < given.size(); ++i) diff |= static_cast<unsigned char>(given[i] ^ token[i]);
  return diff == 0;
}

std::string percentDecoded(std::string_view text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '%' && i + 2 < text.size() && std::isxdigit(static_cast<unsigned char>(text[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(text[i + 2]))) {
      out += static_cast<char>(std::stoi(std::string(text.substr(i + 1, 2)), nullptr, 16));
      i += 2;
    } else {
      out += text[i] == '+' ? ' ' : text[i];
    }
  }
  return out;
}

// The value of `key` in the target's query string.
std::optional<std::string> queryParameter(std::string_view target, std::string_view key) {
  const size_t q = target.find('?');
  if (q == std::string_view::npos) return std::nullopt;
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    const size_t amp = rest.find('&');
    const std::string_view pair = rest.substr(0, amp);
    const size_t eq = pair.find('=');
    if (pair.substr(0, eq) == key) return percentDecoded(eq == std::string_view::npos ? "" : pair.substr(eq + 1));
    if (amp == std::string_view::npos) break;
    rest = rest.substr(amp + 1);
  }
  return std::nullopt;
}

std::string targetOf(const http::request<http::string_body>& request) {
  return std::string(request.target().data(), request.target().size());
}

// The token the request carries: `Authorization: Bearer <token>`, else `?token=<token>`.
std::optional<std::string> tokenOf(const http::request<http::string_body>& request) {
  const auto header = request.find(http::field::authorization);
  if (header != request.end()) {
    const std::string value(header->value());
    static const std::string kPrefix = "Bearer ";
    if (value.rfind(kPrefix, 0) == 0) return value.substr(kPrefix.size());
  }
  return queryParameter(targetOf(request), "token");
}

bool authorized(const http::request<http::string_body>& request, const std::vector<std::string>& tokens) {
  if (tokens.empty()) return true;
  const std::optional<std::string> given = tokenOf(request);
  if (!given) return false;
  bool match = false;  // every token compared, in constant time
  for (const std::string& token : tokens) match |= equalConstantTime(*given, token);
  return match;
}

bool offersSubprotocol(const http::request<http::string_body>& request) {
  const auto header = request.find(http::field::sec_websocket_protocol);
  if (header == request.end()) return false;
  std::stringstream list{std::string(header->value())};
  std::string item;
  while (std::getline(list, item, ',')) {
    const size_t b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b != std::string::npos && item.substr(b, e - b + 1) == kSubprotocol) return true;
  }
  return false;
}

const char* contentType(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".png") return "image/png";
  if (ext == ".json") return "application/json";
  return "application/octet-stream";
}

using TlsStream = beast::ssl_stream<beast::tcp_stream>;

// A viewer client's WebSocket, over plain TCP or over TLS.
class Session : public ClientLink {
 public:
  // On the network thread.
  virtual void close() = 0;
};

// Stream: beast::tcp_stream or TlsStream, the connection the upgrade request came on.
template <class Stream>
class WsSession final : public Session, public std::enable_shared_from_this<WsSession<Stream>> {
 public:
  explicit WsSession(Stream&& stream) : ws_(std::move(stream)) {}

  void start(http::request<http::string_body> request, std::function<void(std::shared_ptr<Session>)> on_open) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& response) {
      response.set(http::field::sec_websocket_protocol, kSubprotocol);
      response.set(http::field::server, "cenote-viewer");
    }));
    ws_.read_message_max(kMaxClientMessageBytes);
    ws_.async_accept(request, [self = this->shared_from_this(), on_open = std::move(on_open)](beast::error_code ec) {
      if (ec) return;
      self->open_ = true;
      on_open(self);
      self->read();
    });
  }

  void send(std::string message, bool binary) override {
    if (!open_) return;
    unsent_ += message.size();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back({std::move(message), binary});
    }
    net::post(ws_.get_executor(), [self = this->shared_from_this()] { self->write(); });
  }
  size_t unsentBytes() const override { return unsent_.load(); }
  bool isOpen() const override { return open_.load(); }

  void close() override {
    open_ = false;
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
    beast::get_lowest_layer(ws_).close();
  }

 private:
  struct Outgoing {
    std::string data;
    bool binary = false;
  };

  void read() {
    ws_.async_read(buffer_, [self = this->shared_from_this()](beast::error_code ec, size_t) {
      if (ec) {
        self->open_ = false;
        return;
      }
      if (self->ws_.got_text()) {
        self->receiveText(beast::buffers_to_string(self->buffer_.data()));
      } else {
        self->receiveBinary();
      }
      self->buffer_.consume(self->buffer_.size());
      self->read();
    });
  }

  void write() {
    if (writing_) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (queue_.empty()) return;
      current_ = std::move(queue_.front());
      queue_.pop_front();
    }
    writing_ = true;
    ws_.binary(current_.binary);
    ws_.async_write(net::buffer(current_.data), [self = this->shared_from_this()](beast::error_code ec, size_t) {
      self->writing_ = false;
      self->unsent_ -= self->current_.data.size();
      self->current_.data = std::string();
      if (ec) {
        self->open_ = false;
        std::lock_guard<std::mutex> lock(self->mutex_);
        for (const Outgoing& o : self->queue_) self->unsent_ -= o.data.size();
        self->queue_.clear();
        return;
      }
      self->write();
    });
  }

  websocket::stream<Stream> ws_;
  beast::flat_buffer buffer_;
  std::mutex mutex_;
  std::deque<Outgoing> queue_;
  Outgoing current_;
  bool writing_ = false;  // network thread only
  std::atomic<bool> open_{false};
  std::atomic<size_t> unsent_{0};
};

}  // namespace

struct ViewerServer::Impl {
  Impl(const ViewerConfig& c, ViewerSources s)
      : config(c),
        sources(std::move(s)),
        web_dir(c.web_dir.empty() ? fs::path(CENOTE_WEB_DIR) : fs::path(c.web_dir)),
        session_id(std::to_string(std::chrono::system_clock::now().time_since_epoch().count())),
        acceptor(io),
        worker(config, sources) {}

  void accept();
  // HTTP requests on one connection until it closes or upgrades to the WebSocket.
  template <class Stream>
  void serveHttp(std::shared_ptr<Stream> stream, std::shared_ptr<beast::flat_buffer> buffer);
  http::response<http::string_body> fileResponse(const http::request<http::string_body>& request) const;

  ViewerConfig config;
  ViewerSources sources;
  fs::path web_dir;
  std::string session_id;
  net::io_context io{1};
  tcp::acceptor acceptor;
  std::unique_ptr<net::ssl::context> tls;  // null: plain TCP
  FeedWorker worker;
  std::mutex sessions_mutex;
  std::vector<std::weak_ptr<Session>> sessions;
  std::thread io_thread;
  bool stopped = false;
};

namespace {

http::response<http::string_body> textResponse(const http::request<http::string_body>& request, http::status status,
                                               const std::string& text) {
  http::response<http::string_body> response{status, request.version()};
  response.set(http::field::server, "cenote-viewer");
  response.set(http::field::content_type, "text/plain; charset=utf-8");
  response.keep_alive(request.keep_alive());
  response.body() = text + "\n";
  response.prepare_payload();
  return response;
}

}  // namespace

http::response<http::string_body> ViewerServer::Impl::fileResponse(const http::request<http::string_body>& request) const {
  if (request.method() != http::verb::get && request.method() != http::verb::head) {
    return textResponse(request, http::status::method_not_allowed, "only GET is served here");
  }
  std::string path = targetOf(request);
  path = path.substr(0, path.find('?'));
  if (path == "/") path = "/index.html";
  const std::string name = path.substr(1);
  const bool plain = !name.empty() &&
                     name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") ==
                         std::string::npos &&
                     name[0] != '.';
  const fs::path file = web_dir / name;
  if (!plain || !fs::is_regular_file(file)) {
    if (name == "index.html") {
      return textResponse(request, http::status::not_found,
                          "the browser viewer is not built (no " + file.string() +
                              "): build the cenote_web target; Foxglove and Lichtblick connect to ws://" +
                              "this address all the same");
    }
    return textResponse(request, http::status::not_found, "no such file: " + path);
  }
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  http::response<http::string_body> response{http::status::ok, request.version()};
  response.set(http::field::server, "cenote-viewer");
  response.set(http::field::content_type, contentType(file));
  response.set(http::field::cache_control, "no-cache");
  response.keep_alive(request.keep_alive());
  response.body() = request.method() == http::verb::head ? std::string() : bytes.str();
  response.prepare_payload();
  return response;
}

void ViewerServer::Impl::accept() {
  acceptor.async_accept(net::make_strand(io), [this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (!acceptor.is_open()) return;
    } else if (!tls) {
      serveHttp(std::make_shared<beast::tcp_stream>(std::move(socket)), std::make_shared<beast::flat_buffer>());
    } else {
      auto stream = std::make_shared<TlsStream>(std::move(socket), *tls);
      beast::get_lowest_layer(*stream).expires_after(std::chrono::seconds(30));
      stream->async_handshake(net::ssl::stream_base::server, [this, stream](beast::error_code ec) {
        if (!ec) serveHttp(stream, std::make_shared<beast::flat_buffer>());  // else: not TLS, or refused
      });
    }
    accept();
  });
}

template <class Stream>
void ViewerServer::Impl::serveHttp(std::shared_ptr<Stream> stream, std::shared_ptr<beast::flat_buffer> buffer) {
  auto parser = std::make_shared<http::request_parser<http::string_body>>();
  parser->header_limit(kMaxRequestHeaderBytes);
  parser->body_limit(kMaxClientMessageBytes);
  beast::get_lowest_layer(*stream).expires_after(std::chrono::seconds(30));
  http::async_read(*stream, *buffer, *parser, [this, stream, buffer, parser](beast::error_code ec, size_t) {
    if (ec) return;  // the connection closes
    http::request<http::string_body> request = parser->release();
    auto reply = [this, stream, buffer](http::response<http::string_body> response) {
      auto kept = std::make_shared<http::response<http::string_body>>(std::move(response));
      http::async_write(*stream, *kept, [this, stream, buffer, kept](beast::error_code ec, size_t) {
        if (ec || !kept->keep_alive()) {
          beast::error_code ignored;
          beast::get_lowest_layer(*stream).socket().shutdown(tcp::socket::shutdown_send, ignored);
          return;
        }
        serveHttp(stream, buffer);
      });
    };
    if (!websocket::is_upgrade(request)) {
      reply(fileResponse(request));
      return;
    }
    if (!authorized(request, sources.tokens)) {
      request.keep_alive(false);
      reply(textResponse(request, http::status::unauthorized,
                         "missing or wrong token: send 'Authorization: Bearer <token>' or ?token=<token>"));
      return;
    }
    if (!offersSubprotocol(request)) {
      request.keep_alive(false);
      reply(textResponse(request, http::status::bad_request,
                         std::string("WebSocket subprotocol ") + kSubprotocol + " required (Sec-WebSocket-Protocol)"));
      return;
    }
    beast::get_lowest_layer(*stream).expires_never();
    auto session = std::make_shared<WsSession<Stream>>(std::move(*stream));
    {
      std::lock_guard<std::mutex> lock(sessions_mutex);
      sessions.erase(std::remove_if(sessions.begin(), sessions.end(), [](const auto& w) { return w.expired(); }),
                     sessions.end());
      sessions.push_back(session);
    }
    session->start(std::move(request), [this](std::shared_ptr<Session> open) {
      open->greet(sources.server_name, session_id);
      worker.add(std::move(open));
    });
  });
}

namespace {

// The server's side of TLS from PEM files. @throws cenote::Error naming the key and the file.
std::unique_ptr<net::ssl::context> tlsContext(const ViewerConfig& config) {
  auto context = std::make_unique<net::ssl::context>(net::ssl::context::tls_server);
  context->set_options(net::ssl::context::default_workarounds | net::ssl::context::no_sslv2 | net::ssl::context::no_sslv3 |
                       net::ssl::context::no_tlsv1 | net::ssl::context::no_tlsv1_1);
  beast::error_code ec;
  context->use_certificate_chain_file(config.tls_cert_file, ec);
  if (ec) throw Error("server.viewer.tls_cert_file = " + config.tls_cert_file + ": " + ec.message());
  context->use_private_key_file(config.tls_key_file, net::ssl::context::pem, ec);
  if (ec) throw Error("server.viewer.tls_key_file = " + config.tls_key_file + ": " + ec.message());
  return context;
}

}  // namespace

ViewerServer::ViewerServer(const ViewerConfig& config, ViewerSources sources)
    : impl_(std::make_unique<Impl>(config, std::move(sources))) {
  const size_t colon = config.listen.rfind(':');
  if (colon == std::string::npos) throw Error("server.viewer.listen = " + config.listen + ": must be HOST:PORT");
  std::string host = config.listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  const std::string port = config.listen.substr(colon + 1);
  beast::error_code ec;
  tcp::resolver resolver(impl_->io);
  const auto endpoints = resolver.resolve(host, port, ec);
  if (ec || endpoints.empty()) {
    throw Error("server.viewer.listen = " + config.listen + ": cannot resolve '" + host + "': " + ec.message());
  }
  if (!config.tls_cert_file.empty()) impl_->tls = tlsContext(config);
  const tcp::endpoint endpoint = endpoints.begin()->endpoint();
  tcp::acceptor& a = impl_->acceptor;
  a.open(endpoint.protocol(), ec);
  if (!ec) a.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(endpoint, ec);
  if (!ec) a.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw Error("server.viewer.listen = " + config.listen + ": cannot listen: " + ec.message());
  impl_->accept();
  impl_->io_thread = std::thread([this] {
    nameThisThread("viewer-net");
    impl_->io.run();
  });
}

ViewerServer::~ViewerServer() { stop(); }

bool ViewerServer::usesTls() const { return impl_->tls != nullptr; }

std::string ViewerServer::urls(const std::string& host) const {
  const std::string secure = usesTls() ? "s" : "", address = host + ":" + std::to_string(port());
  return "http" + secure + "://" + address + "/ (Foxglove: ws" + secure + "://" + address + ")";
}

int ViewerServer::port() const { return impl_->acceptor.is_open() ? impl_->acceptor.local_endpoint().port() : 0; }

void ViewerServer::stop() {
  if (impl_->stopped) return;
  impl_->stopped = true;
  impl_->worker.stop();
  std::promise<void> closed;
  net::post(impl_->io, [this, &closed] {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    std::lock_guard<std::mutex> lock(impl_->sessions_mutex);
    for (const auto& weak : impl_->sessions)
      if (auto s = weak.lock()) s->close();
    closed.set_value();
  });
  closed.get_future().wait();
  impl_->io.stop();  // idle HTTP connections and handlers still pending are dropped
  if (impl_->io_thread.joinable()) impl_->io_thread.join();
}

uint64_t ViewerServer::bytesSent() const { return impl_->worker.bytesSent(); }

size_t ViewerServer::clients() const { return impl_->worker.clients(); }

}  // namespace cenote::server::viewer
