#include "server/web/web_server.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <deque>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "client/net/net_driver.hpp"
#include "common/auth/join_token.hpp"
#include "common/auth/token_command.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/tls/tls_context.hpp"
#include "server/web/avatar_glb.hpp"
#include "server/web/spectator_stream.hpp"
#include "server/web/web_assets.hpp"
#include "server/web/web_beast.hpp"
#include "server/web/web_limits.hpp"
#include "server/web/web_member.hpp"
#include "server/web/web_pages.hpp"

namespace vistel::server {
namespace {

using tcp = asio::ip::tcp;
using Strand = asio::strand<asio::io_context::executor_type>;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kMaxWsMessageBytes = 1024;  // from the browser (a visible spectator's)
constexpr double kWsMessageRateHz = 20.0;         // ... sustained
constexpr double kWsMessageBurst = 40.0;

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

template <typename F>
void guarded(const char* where, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    spdlog::error("web: {}: unexpected exception: {}", where, e.what());
  } catch (...) {
    spdlog::error("web: {}: unexpected exception", where);
  }
}

beast::string_view bsv(std::string_view s) { return {s.data(), s.size()}; }

// Indices into WebServer::kRouteClasses.
constexpr std::size_t kWebSocketRoute = 4;
constexpr std::size_t kOtherRoute = 5;
std::size_t routeClass(WebRoute route) {
  switch (route) {
    case WebRoute::kRoomList:
    case WebRoute::kRoomsJson:
      return 0;
    case WebRoute::kRoomPage:
      return 1;
    case WebRoute::kAsset:
      return 2;
    case WebRoute::kAvatar:
      return 3;
    case WebRoute::kRoomSocket:
      return kWebSocketRoute;
    case WebRoute::kNotFound:
      break;
  }
  return kOtherRoute;
}

// Something stop() must close.
struct Closable {
  virtual ~Closable() = default;
  virtual void close() = 0;
};

}  // namespace

class RoomFeed;
class WsSession;

struct WebServer::State : std::enable_shared_from_this<WebServer::State> {
  State(asio::io_context& io_context, ServerShell& server_shell, WebServerOptions opts)
      : io(io_context),
        shell(server_shell),
        options(std::move(opts)),
        accept_strand(asio::make_strand(io_context)),
        acceptor(accept_strand),
        accept_timer(accept_strand),
        limits(options.config),
        start(Clock::now()) {}

  double now() const { return std::chrono::duration<double>(Clock::now() - start).count(); }
  double streamRateHz() const {
    return std::clamp(options.tick_rate_hz, 1.0, options.config.max_stream_rate_hz);
  }
  bool roomsHidden() const {
    return !options.join_secret.empty() && !options.config.public_room_list;
  }

  void accept();
  void track(std::uint64_t id, std::weak_ptr<Closable> c) {
    std::lock_guard lock(mutex);
    open[id] = std::move(c);
  }
  void untrack(std::uint64_t id) {
    std::lock_guard lock(mutex);
    open.erase(id);
  }
  void count(std::uint64_t Stats::*field, std::uint64_t n = 1) {
    std::lock_guard lock(mutex);
    stats.*field += n;
  }
  // An answer of `status` to a request of route class `route` (WebServer::kRouteClasses).
  void answered(std::size_t route, int status) {
    const int status_class = std::clamp(status / 100, 1, 5) - 1;
    std::lock_guard lock(mutex);
    ++stats.answers[std::min<std::size_t>(route, stats.answers.size() - 1)]
                   [static_cast<std::size_t>(status_class)];
  }
  void refused(std::string_view reason) {
    std::lock_guard lock(mutex);
    auto it = stats.refusals.find(reason);
    if (it == stats.refusals.end()) it = stats.refusals.emplace(std::string(reason), 0).first;
    ++it->second;
  }
  // The .glb of an avatar (cached), or null; reply on any thread.
  void avatarGlbOf(const std::string& hash,
                   std::function<void(std::shared_ptr<const std::vector<std::uint8_t>>)> reply);
  // The visible spectators' avatar (made once, web_member.hpp).
  struct MemberAvatar {
    std::shared_ptr<const std::vector<std::uint8_t>> bytes;
    std::string hash;
    int joint_count = 0;
  };
  const MemberAvatar& memberAvatar() {
    std::call_once(member_avatar_once, [this] {
      const AvatarModel model = makeSpectatorAvatar();
      auto bytes = std::make_shared<const std::vector<std::uint8_t>>(encodeAvatar(model));
      member_avatar.hash = avatarContentHash(*bytes);
      member_avatar.bytes = std::move(bytes);
      member_avatar.joint_count = model.skeleton.jointCount();
    });
    return member_avatar;
  }
  // Where visible spectators join: the session server on this host.
  net::ServerAddress sessionAddress() const {
    std::string host = options.bind_address;
    if (host == "0.0.0.0" || host.empty()) host = "127.0.0.1";
    if (host == "::") host = "::1";
    return {host, options.session_port};
  }
  // A spectator joins / leaves its room's feed.
  bool joinFeed(const std::string& room, const std::shared_ptr<WsSession>& session);
  void leaveFeed(const std::string& room, WsSession* session);

  asio::io_context& io;
  ServerShell& shell;
  WebServerOptions options;
  Strand accept_strand;
  tcp::acceptor acceptor;
  asio::steady_timer accept_timer;
  std::atomic<bool> stopping{false};
  std::atomic<std::uint64_t> next_id{1};

  std::mutex mutex;  // everything below
  WebLimits limits;
  Stats stats;
  std::unordered_map<std::uint64_t, std::weak_ptr<Closable>> open;
  std::map<std::string, std::shared_ptr<RoomFeed>, std::less<>> feeds;
  std::list<std::pair<std::string, std::shared_ptr<const std::vector<std::uint8_t>>>> glb_cache;
  int visible_members = 0;  // visible spectators (joined or joining) now
  Clock::time_point start;
  std::once_flag member_avatar_once;
  MemberAvatar member_avatar;
};

using State = WebServer::State;

namespace {

// A connection's place in WebLimits, given back when the last owner goes.
struct Admission {
  Admission(std::shared_ptr<State> s, std::string a) : state(std::move(s)), address(std::move(a)) {}
  ~Admission() {
    std::lock_guard lock(state->mutex);
    state->limits.release(address);
  }
  std::shared_ptr<State> state;
  std::string address;
};

}  // namespace

// ---------------------------------------------------------------- WebSocket spectators

class WsSession : public Closable, public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(std::shared_ptr<Admission> admission, beast::tcp_stream stream, std::string room,
            std::string token)
      : admission_(std::move(admission)),
        state_(admission_->state),
        ws_(std::move(stream)),
        room_(std::move(room)),
        token_(std::move(token)),
        id_(state_->next_id++),
        bucket_(kWsMessageRateHz, kWsMessageBurst, state_->now()),
        member_timer_(ws_.get_executor()) {}
  ~WsSession() override {
    if (driver_) driver_->stop("spectator left");
    if (counted_member_) {
      std::lock_guard lock(state_->mutex);
      --state_->visible_members;
    }
    state_->untrack(id_);
  }

  void start(http::request<http::empty_body> request) {
    state_->track(id_, weak_from_this());
    beast::get_lowest_layer(ws_).expires_never();
    websocket::stream_base::timeout timeout =
        websocket::stream_base::timeout::suggested(beast::role_type::server);
    timeout.handshake_timeout = seconds(state_->options.config.read_timeout_s);
    timeout.idle_timeout = seconds(state_->options.config.idle_timeout_s);
    timeout.keep_alive_pings = true;
    ws_.set_option(timeout);
    ws_.read_message_max(kMaxWsMessageBytes);
    ws_.auto_fragment(false);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(http::field::server, "vistel"); }));
    ws_.async_accept(request, beast::bind_front_handler(&WsSession::onAccept, shared_from_this()));
  }

  // Queues a message (any thread). A binary frame replaces an older frame still waiting.
  void send(std::shared_ptr<const std::string> text, bool binary) {
    asio::post(ws_.get_executor(), [self = shared_from_this(), text, binary] {
      self->enqueue(std::move(text), binary);
    });
  }

  void close() override {
    asio::post(ws_.get_executor(), [self = shared_from_this()] {
      self->closeNow(websocket::close_code::going_away, "server stopping");
    });
  }

 private:
  struct Out {
    std::shared_ptr<const std::string> bytes;
    bool binary = false;
  };

  void onAccept(beast::error_code ec) {
    state_->answered(kWebSocketRoute, ec ? 400 : 101);
    if (ec) {
      finish();
      return;
    }
    accepted_ = true;
    state_->count(&WebServer::Stats::spectators);
    // Join tokens: the room must be one the token admits to (any name).
    if (!state_->options.join_secret.empty()) {
      std::string why;
      if (token_.empty()) {
        why = "this room needs a join token (?token=...)";
      } else {
        auto claims = auth::parseJoinToken(token_);
        const auth::TokenCheck check =
            auth::verifyJoinToken(state_->options.join_secret, token_, room_,
                                  claims ? claims->name : std::string(), auth::unixNow());
        if (!check.ok()) why = fmt::format("join token refused: {}", check.message);
      }
      if (!why.empty()) {
        spdlog::info("web: spectator of room '{}' from {} refused: {}", room_, admission_->address,
                     why);
        state_->count(&WebServer::Stats::unauthorized);
        state_->refused("token");
        enqueue(std::make_shared<const std::string>(statusJson("unauthorized", why)), false);
        close_after_flush_ = true;
        close_code_ = websocket::close_code::policy_error;
        flush();
        return;
      }
    }
    if (!state_->joinFeed(room_, shared_from_this())) {
      state_->refused("spectators per room");
      enqueue(std::make_shared<const std::string>(
                  statusJson("full", "too many spectators in this room; try again later")),
              false);
      close_after_flush_ = true;
      close_code_ = websocket::close_code::try_again_later;
      flush();
      return;
    }
    joined_ = true;
    state_->count(&WebServer::Stats::spectators_open);
    read();
  }

  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) {
        self->finish();
        return;
      }
      // A browser that floods is dropped.
      if (!self->bucket_.take(self->state_->now())) {
        self->in_.consume(self->in_.size());
        self->closeNow(websocket::close_code::policy_error, "too many messages");
        return;
      }
      const std::string text = beast::buffers_to_string(self->in_.data());
      self->in_.consume(self->in_.size());
      if (!self->ws_.got_text()) {
        self->badMessage("a binary message (the page sends JSON text)");
      } else {
        guarded("spectator message", [&] { self->onMessage(text); });
      }
      self->read();
    });
  }

  void enqueue(std::shared_ptr<const std::string> bytes, bool binary) {
    if (closing_) return;
    if (binary && !queue_.empty() && queue_.back().binary && (queue_.size() > 1 || !writing_)) {
      queued_bytes_ -= queue_.back().bytes->size();
      queue_.back().bytes = std::move(bytes);  // the older frame is skipped
      queued_bytes_ += queue_.back().bytes->size();
      state_->count(&WebServer::Stats::frames_skipped);
    } else {
      queued_bytes_ += bytes->size();
      queue_.push_back({std::move(bytes), binary});
    }
    if (queued_bytes_ > state_->options.config.max_ws_queue_bytes) {
      spdlog::info("web: spectator of room '{}' from {} is not reading: dropped", room_,
                   admission_->address);
      closing_ = true;
      beast::get_lowest_layer(ws_).close();
      return;
    }
    flush();
  }

  void flush() {
    if (writing_ || closing_) return;
    if (queue_.empty()) {
      if (close_after_flush_) closeNow(close_code_, "");
      return;
    }
    writing_ = true;
    ws_.binary(queue_.front().binary);
    ws_.async_write(asio::buffer(*queue_.front().bytes),
                    [self = shared_from_this()](beast::error_code ec, std::size_t n) {
                      self->writing_ = false;
                      self->state_->count(&WebServer::Stats::ws_bytes_sent, n);
                      const bool binary = self->queue_.front().binary;
                      self->queued_bytes_ -= self->queue_.front().bytes->size();
                      self->queue_.pop_front();
                      if (ec) {
                        self->finish();
                        return;
                      }
                      if (binary) self->state_->count(&WebServer::Stats::frames_sent);
                      if (self->pending_close_) {
                        self->pending_close_ = false;
                        self->closeNow(self->close_code_, "");
                        return;
                      }
                      self->flush();
                    });
  }

  void closeNow(websocket::close_code code, const char* reason) {
    if (closing_) return;
    if (!accepted_) {
      closing_ = true;
      beast::get_lowest_layer(ws_).close();
      return;
    }
    if (writing_) {  // one write at a time: close after it
      pending_close_ = true;
      close_code_ = code;
      return;
    }
    closing_ = true;
    beast::get_lowest_layer(ws_).expires_after(std::chrono::seconds(2));
    ws_.async_close(websocket::close_reason(code, reason),
                    [self = shared_from_this()](beast::error_code) { self->finish(); });
  }

  // ------------------------------------------------ visible spectators (web_member.hpp)

  void badMessage(std::string_view why) {
    spdlog::warn("web: spectator of room '{}' from {}: message dropped: {}", room_,
                 admission_->address, why);
    state_->refused("bad message");
    enqueue(std::make_shared<const std::string>(
                nlohmann::json{{"type", "error"}, {"message", std::string(why)}}.dump()),
            false);
  }

  void memberState(std::string_view state, std::string_view message) {
    nlohmann::json j{{"type", "member"}, {"state", state}, {"message", message}};
    if (member_id_ != 0) j["id"] = member_id_;
    if (!member_name_.empty()) j["name"] = member_name_;
    enqueue(std::make_shared<const std::string>(j.dump()), false);
  }

  void onMessage(const std::string& text) {
    auto msg = parseSpectatorMessage(text);
    if (!msg) {
      badMessage(msg.error().message);
      return;
    }
    switch (msg->kind) {
      case SpectatorMessage::Kind::kJoin:
        joinAsMember(msg->name);
        return;
      case SpectatorMessage::Kind::kPose:
        pose_ = msg->pose;
        has_pose_ = true;
        return;
      case SpectatorMessage::Kind::kLeave:
        if (driver_) {
          stopMember("the page left");
          memberState("left", "no longer visible in the room");
        }
        return;
    }
  }

  void joinAsMember(const std::string& requested) {
    const WebConfig& config = state_->options.config;
    if (!config.members) {
      spdlog::info(
          "web: spectator of room '{}' from {} asked to join as a member: refused "
          "(this server runs without --web-members)",
          room_, admission_->address);
      state_->refused("members off");
      memberState("refused",
                  "this server does not let spectators join as members (vistel-server "
                  "--web-members)");
      return;
    }
    if (driver_) {
      badMessage("already joined as a member");
      return;
    }
    bool room_for_one = false;
    {
      std::lock_guard lock(state_->mutex);
      if (state_->visible_members < config.max_members) {
        ++state_->visible_members;
        room_for_one = true;
      }
    }
    if (!room_for_one) {
      state_->refused("visible spectators");
      memberState("refused", "too many visible spectators on this server; try again later");
      return;
    }
    counted_member_ = true;
    const auto& avatar = state_->memberAvatar();
    net::SessionSettings settings;
    settings.room = room_;
    settings.name = spectatorMemberName(requested, id_);
    member_name_ = settings.name;
    // The socket's token admitted this page to the room; the member gets a token of its
    // own from the same secret (the lobby checks room and name).
    if (!state_->options.join_secret.empty()) {
      auto token = auth::createJoinToken(state_->options.join_secret,
                                         {room_, settings.name, auth::unixNow() + 24 * 3600});
      if (!token) {
        memberState("refused", token.error().message);
        stopMember("no token");
        return;
      }
      settings.token = std::move(*token);
    }
    settings.avatar_bytes = avatar.bytes;
    settings.avatar_hash = avatar.hash;
    settings.avatar_joint_count = avatar.joint_count;
    settings.fetch_avatars = false;
    settings.reconnect_give_up_s = 0.0;  // it lives and dies with this socket
    tls::ClientTlsSettings tls;
    if (!state_->options.tls_cert_file.empty()) {
      auto pin = tls::certificateFingerprint(state_->options.tls_cert_file);
      if (!pin) {
        memberState("refused", pin.error().message);
        stopMember("no TLS pin");
        return;
      }
      tls.enabled = true;
      tls.pin_sha256 = *pin;
    }
    net::BackoffSettings backoff;
    backoff.max_attempts = 2;
    driver_ = net::NetDriver::create(state_->io, state_->sessionAddress(), settings, nullptr,
                                     backoff, tls);
    driver_->start();
    spdlog::info("web: spectator of room '{}' from {} joins as member '{}'", room_,
                 admission_->address, member_name_);
    memberState("joining", "joining the room as a visible spectator");
    armMemberTimer();
  }

  void armMemberTimer() {
    member_timer_.expires_after(seconds(1.0 / state_->options.config.member_pose_rate_hz));
    member_timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || !self->driver_) return;
      guarded("visible spectator", [&] { self->memberTick(); });
      if (self->driver_) self->armMemberTimer();
    });
  }

  // Every 1 / member_pose_rate_hz: tells the page when its member is live or closed, and
  // sends the newest camera pose as the member's posture.
  void memberTick() {
    const net::SessionState s = driver_->state();
    if (s == net::SessionState::kClosed) {
      const std::string why = driver_->error();
      spdlog::info("web: visible spectator '{}' of room '{}' closed: {}", member_name_, room_, why);
      stopMember("closed");
      memberState("refused", why.empty() ? "the session server closed the member" : why);
      return;
    }
    if (s != net::SessionState::kLive) return;
    struct SelfSeat {
      std::uint32_t id = 0;
      bool known = false;
      net::Seat seat;
    };
    const SelfSeat self = driver_->withSession([](const net::ClientSession& session, double) {
      SelfSeat out;
      out.id = session.memberId();
      if (const net::RemoteMember* m = session.findMember(out.id)) {
        out.known = true;
        out.seat = m->seat;
      }
      return out;
    });
    if (!self.known) return;
    if (!live_announced_) {
      live_announced_ = true;
      member_id_ = self.id;
      memberState("live", "visible in the room");
    }
    if (!has_pose_) return;
    driver_->sendPosture(spectatorPosture(pose_, self.seat.x, self.seat.z, self.seat.yaw));
  }

  // The member leaves (its driver sends Leave and closes).
  void stopMember(const char* reason) {
    member_timer_.cancel();
    if (driver_) {
      spdlog::info("web: visible spectator '{}' of room '{}' leaves ({})", member_name_, room_,
                   reason);
      driver_->stop(reason);
      driver_.reset();
    }
    if (counted_member_) {
      counted_member_ = false;
      std::lock_guard lock(state_->mutex);
      --state_->visible_members;
    }
    live_announced_ = false;
    member_id_ = 0;
    has_pose_ = false;
  }

  void finish() {
    stopMember("spectator left");
    if (joined_) {
      joined_ = false;
      state_->leaveFeed(room_, this);
      std::lock_guard lock(state_->mutex);
      --state_->stats.spectators_open;
    }
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

  std::shared_ptr<Admission> admission_;
  std::shared_ptr<State> state_;
  websocket::stream<beast::tcp_stream> ws_;
  std::string room_;
  std::string token_;
  std::uint64_t id_;
  TokenBucket bucket_;
  beast::flat_buffer in_;
  std::deque<Out> queue_;
  std::size_t queued_bytes_ = 0;
  bool accepted_ = false;
  bool joined_ = false;
  bool writing_ = false;
  bool closing_ = false;
  bool pending_close_ = false;
  bool close_after_flush_ = false;
  websocket::close_code close_code_ = websocket::close_code::normal;
  // A visible spectator's member (null: none).
  asio::steady_timer member_timer_;
  std::shared_ptr<net::NetDriver> driver_;
  bool counted_member_ = false;  // in State::visible_members
  bool live_announced_ = false;
  std::uint32_t member_id_ = 0;
  std::string member_name_;
  SpectatorPose pose_;
  bool has_pose_ = false;
};

// ---------------------------------------------------------------- room feeds

// Samples one room at the stream rate and sends every spectator of it the same messages.
class RoomFeed : public std::enable_shared_from_this<RoomFeed> {
 public:
  RoomFeed(std::shared_ptr<State> state, std::string room)
      : state_(std::move(state)),
        room_(std::move(room)),
        strand_(asio::make_strand(state_->io)),
        timer_(strand_) {}

  void add(const std::shared_ptr<WsSession>& s) {
    asio::post(strand_, [self = shared_from_this(), s] {
      self->sessions_.push_back(s);
      s->send(
          std::make_shared<const std::string>(helloJson(self->room_, self->state_->streamRateHz())),
          false);
      if (self->status_) s->send(self->status_, false);
      if (self->roster_) s->send(self->roster_, false);
      if (!self->running_) {
        self->running_ = true;
        self->next_ = Clock::now();
        self->sample();
      }
    });
  }
  void remove(WsSession* s) {
    asio::post(strand_, [self = shared_from_this(), s] {
      std::erase_if(self->sessions_, [s](const std::weak_ptr<WsSession>& w) {
        auto p = w.lock();
        return !p || p.get() == s;
      });
    });
  }
  void stop() {
    asio::post(strand_, [self = shared_from_this()] {
      self->stopped_ = true;
      self->timer_.cancel();
    });
  }
  std::size_t members_ = 0;  // spectators, counted by State under its mutex

 private:
  void sample() {
    if (stopped_ || state_->stopping) return;
    std::erase_if(sessions_, [](const std::weak_ptr<WsSession>& w) { return w.expired(); });
    if (sessions_.empty()) {
      running_ = false;
      return;
    }
    state_->shell.spectate(room_, [self = shared_from_this()](std::optional<SpectatorFrame> frame) {
      asio::post(self->strand_, [self, frame = std::move(frame)]() mutable {
        guarded("room feed", [&] { self->onFrame(std::move(frame)); });
        self->arm();
      });
    });
  }

  void arm() {
    if (stopped_ || state_->stopping) return;
    next_ += seconds(1.0 / state_->streamRateHz());
    const auto t = Clock::now();
    if (next_ < t) next_ = t;  // late: skip, do not catch up
    timer_.expires_at(next_);
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->sample();
    });
  }

  void setStatus(std::string_view state, std::string_view message) {
    if (state == status_name_) return;
    status_name_ = std::string(state);
    status_ = std::make_shared<const std::string>(statusJson(state, message));
    broadcast(status_, false);
  }

  void onFrame(std::optional<SpectatorFrame> frame) {
    if (!frame) {
      if (status_name_ == "live" || status_name_ == "closed") {
        setStatus("closed", fmt::format("room '{}' closed: everyone left", room_));
      } else {
        setStatus("absent", fmt::format("room '{}' is empty: nobody is in it", room_));
      }
      roster_.reset();
      roster_text_.clear();
      return;
    }
    setStatus("live", fmt::format("watching room '{}'", room_));
    std::string roster = rosterJson(frame->room, state_->options.seat_layout);
    if (roster != roster_text_) {
      roster_text_ = roster;
      roster_ = std::make_shared<const std::string>(std::move(roster));
      broadcast(roster_, false);
    }
    encodeSpectatorFrame(*frame, scratch_);
    broadcast(std::make_shared<const std::string>(scratch_.begin(), scratch_.end()), true);
  }

  void broadcast(const std::shared_ptr<const std::string>& bytes, bool binary) {
    for (const std::weak_ptr<WsSession>& w : sessions_) {
      if (auto s = w.lock()) s->send(bytes, binary);
    }
  }

  std::shared_ptr<State> state_;
  std::string room_;
  Strand strand_;
  asio::steady_timer timer_;
  std::vector<std::weak_ptr<WsSession>> sessions_;
  bool running_ = false;
  bool stopped_ = false;
  Clock::time_point next_;
  std::string status_name_;
  std::shared_ptr<const std::string> status_;
  std::shared_ptr<const std::string> roster_;
  std::string roster_text_;
  std::vector<std::uint8_t> scratch_;
};

bool State::joinFeed(const std::string& room, const std::shared_ptr<WsSession>& session) {
  std::shared_ptr<RoomFeed> feed;
  {
    std::lock_guard lock(mutex);
    auto it = feeds.find(room);
    if (it == feeds.end()) {
      it = feeds.emplace(room, std::make_shared<RoomFeed>(shared_from_this(), room)).first;
    }
    if (it->second->members_ >= static_cast<std::size_t>(options.config.max_spectators_per_room)) {
      return false;
    }
    ++it->second->members_;
    feed = it->second;
  }
  feed->add(session);
  return true;
}

void State::leaveFeed(const std::string& room, WsSession* session) {
  std::lock_guard lock(mutex);
  auto it = feeds.find(room);
  if (it == feeds.end()) return;
  it->second->remove(session);
  if (--it->second->members_ == 0) {
    it->second->stop();
    feeds.erase(it);
  }
}

void State::avatarGlbOf(
    const std::string& hash,
    std::function<void(std::shared_ptr<const std::vector<std::uint8_t>>)> reply) {
  {
    std::lock_guard lock(mutex);
    for (auto it = glb_cache.begin(); it != glb_cache.end(); ++it) {
      if (it->first != hash) continue;
      glb_cache.splice(glb_cache.begin(), glb_cache, it);  // most recent first
      reply(glb_cache.front().second);
      return;
    }
  }
  shell.avatarFile(hash, [self = shared_from_this(), hash, reply = std::move(reply)](
                             std::shared_ptr<const std::vector<std::uint8_t>> file) {
    if (!file) {
      reply(nullptr);
      return;
    }
    // Convert off the lobby strand.
    asio::post(self->io, [self, hash, file, reply] {
      std::shared_ptr<const std::vector<std::uint8_t>> glb;
      guarded("avatar glb", [&] {
        auto model = decodeAvatar(*file, hash);
        if (!model) {
          spdlog::warn("web: avatar {}: {}", hash.substr(0, 12), model.error().message);
          return;
        }
        auto bytes = avatarGlb(*model);
        if (!bytes) {
          spdlog::warn("web: avatar {}: {}", hash.substr(0, 12), bytes.error().message);
          return;
        }
        glb = std::make_shared<const std::vector<std::uint8_t>>(std::move(*bytes));
        std::lock_guard lock(self->mutex);
        self->glb_cache.emplace_front(hash, glb);
        while (self->glb_cache.size() > WebServer::kGlbCacheEntries) self->glb_cache.pop_back();
      });
      reply(glb);
    });
  });
}

// ---------------------------------------------------------------- HTTP

namespace {

class HttpSession : public Closable, public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(std::shared_ptr<Admission> admission, tcp::socket socket)
      : admission_(std::move(admission)),
        state_(admission_->state),
        stream_(std::move(socket)),
        executor_(stream_.get_executor()),
        id_(state_->next_id++) {}
  ~HttpSession() override { state_->untrack(id_); }

  void start() {
    state_->track(id_, weak_from_this());
    readHead(state_->options.config.read_timeout_s);
  }
  void close() override {
    asio::post(executor_, [self = shared_from_this()] {
      if (self->upgraded_) return;  // the stream went to a WsSession
      beast::error_code ignored;
      self->stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
      self->stream_.close();
    });
  }

 private:
  using Response = http::response<http::span_body<const char>>;

  void readHead(double timeout_s) {
    route_class_ = kOtherRoute;
    parser_.emplace();
    configureHeadParser(*parser_, state_->options.config.max_header_bytes);
    stream_.expires_after(seconds(timeout_s));
    http::async_read_header(stream_, buffer_, *parser_,
                            beast::bind_front_handler(&HttpSession::onHead, shared_from_this()));
  }

  void onHead(beast::error_code ec, std::size_t) {
    if (ec == http::error::end_of_stream || ec == asio::error::operation_aborted ||
        ec == asio::error::connection_reset || ec == asio::error::eof) {
      stream_.close();
      return;
    }
    if (ec == beast::error::timeout) {
      state_->count(&WebServer::Stats::timed_out);
      stream_.close();
      return;
    }
    if (state_->stopping) {
      stream_.close();
      return;
    }
    // Every head read counts against the address's rate, malformed ones too.
    bool allowed;
    {
      std::lock_guard lock(state_->mutex);
      allowed = state_->limits.allowRequest(admission_->address, state_->now());
    }
    if (!allowed) {
      state_->count(&WebServer::Stats::rate_limited);
      respondError(429, "too many requests: slow down", false);
      return;
    }
    if (ec) {
      respondError(statusOfParseError(ec), ec.message(), false);
      return;
    }
    const auto& req = parser_->get();
    keep_alive_ = req.keep_alive();
    const RequestHead head = requestHeadOf(req);
    if (!hostAllowed(head.host, state_->options.config.allowed_hosts)) {
      // A name this server does not go by: possibly a page whose DNS was rebound to us.
      spdlog::info("web: request from {} for Host '{}' refused (not an allowed host name)",
                   admission_->address, head.host.substr(0, 100));
      state_->refused("host");
      respondError(421, "this server does not answer to that Host name ([web] allowed_hosts)",
                   false);
      return;
    }
    RequestVerdict verdict = judgeRequest(head);
    route_class_ = routeClass(verdict.target.route);
    if (verdict.status != 0) {
      const bool keep =
          (verdict.status == 404 || verdict.status == 426) && !requestHeadOf(req).has_body;
      respondError(verdict.status, verdict.reason, keep);
      return;
    }
    serve(std::move(verdict.target));
  }

  void serve(WebTarget target) {
    auto self = shared_from_this();
    switch (target.route) {
      case WebRoute::kRoomList:
      case WebRoute::kRoomsJson: {
        const bool json = target.route == WebRoute::kRoomsJson;
        state_->shell.roomViews([self, json](std::vector<LobbyRoomView> rooms, double now) {
          // The page is made on this connection's strand, not the lobby's.
          asio::post(self->executor_, [self, json, rooms = std::move(rooms), now] {
            const bool hidden = self->state_->roomsHidden();
            auto body = std::make_shared<const std::string>(
                json ? roomListJson(rooms, now, hidden) : roomListHtml(rooms, now, hidden));
            self->respond(200, json ? "application/json" : "text/html; charset=utf-8", *body, body,
                          "no-store", !json);
          });
        });
        return;
      }
      case WebRoute::kRoomPage:
        serveAsset("spectator.html");
        return;
      case WebRoute::kAsset:
        serveAsset(target.asset);
        return;
      case WebRoute::kAvatar:
        state_->avatarGlbOf(target.hash, [self](
                                             std::shared_ptr<const std::vector<std::uint8_t>> glb) {
          asio::post(self->executor_, [self, glb] {
            if (!glb) {
              self->respondError(404, "no such avatar on this server", true);
              return;
            }
            self->respond(200, "model/gltf-binary",
                          std::string_view(reinterpret_cast<const char*>(glb->data()), glb->size()),
                          glb, "public, max-age=86400, immutable", false);
          });
        });
        return;
      case WebRoute::kRoomSocket: {
        upgraded_ = true;
        state_->untrack(id_);
        auto ws = std::make_shared<WsSession>(admission_, std::move(stream_), target.room,
                                              std::move(target.token));
        ws->start(parser_->release());
        return;
      }
      case WebRoute::kNotFound:
        break;
    }
    respondError(404, "no such page", true);
  }

  void serveAsset(std::string_view name) {
    const WebAsset* asset = findWebAsset(name);
    if (asset == nullptr) {
      respondError(404, "no such file", true);
      return;
    }
    const std::string etag = fmt::format("\"{}\"", asset->sha256.substr(0, 32));
    const auto& req = parser_->get();
    if (auto it = req.find(http::field::if_none_match);
        it != req.end() && it->value() == bsv(etag)) {
      respond(304, asset->content_type, {}, nullptr, "no-cache", false, etag);
      return;
    }
    respond(
        200, asset->content_type,
        std::string_view(reinterpret_cast<const char*>(asset->bytes.data()), asset->bytes.size()),
        nullptr, "no-cache", name.ends_with(".html"), etag);
  }

  void respondError(int status, std::string_view reason, bool keep) {
    state_->count(&WebServer::Stats::errors);
    // 429 is counted by WebLimits ("request rate"), 421 as "host"; a 404 is an answer, not
    // a refusal.
    if (status != 404 && status != 421 && status != 429 && status < 500) {
      state_->refused("bad request");
    }
    auto body = std::make_shared<const std::string>(
        fmt::format("{} {}: {}\n", status, statusText(status), reason));
    if (!keep) keep_alive_ = false;
    respond(status, "text/plain; charset=utf-8", *body, body, "no-store", false);
  }

  // Writes a response whose body `bytes` stays valid while `keep` (or static data) lives.
  void respond(int status, std::string_view content_type, std::string_view bytes,
               std::shared_ptr<const void> keep, std::string_view cache, bool html,
               std::string_view etag = {}) {
    state_->count(&WebServer::Stats::requests);
    state_->answered(route_class_, status);
    keep_ = std::move(keep);
    auto res = std::make_shared<Response>();
    res->result(static_cast<unsigned>(status));
    res->version(11);
    res->set(http::field::server, "vistel");
    res->set(http::field::content_type, bsv(content_type));
    res->set(http::field::cache_control, bsv(cache));
    res->set("X-Content-Type-Options", "nosniff");
    res->set("Referrer-Policy", "no-referrer");  // tokens travel in query strings
    if (!etag.empty()) res->set(http::field::etag, bsv(etag));
    if (status == 405) res->set(http::field::allow, "GET");
    if (html) {
      res->set("Content-Security-Policy",
               "default-src 'self'; connect-src 'self' ws: wss:; img-src 'self' data: blob:; "
               "script-src 'self'; style-src 'self'; frame-ancestors 'none'");
    }
    if (status != 304)
      res->body() = http::span_body<const char>::value_type(bytes.data(), bytes.size());
    res->keep_alive(keep_alive_);
    res->prepare_payload();
    stream_.expires_after(seconds(state_->options.config.write_timeout_s));
    http::async_write(stream_, *res,
                      [self = shared_from_this(), res](beast::error_code ec, std::size_t n) {
                        self->keep_.reset();
                        self->state_->count(&WebServer::Stats::http_bytes_sent, n);
                        if (ec) {
                          if (ec == beast::error::timeout) {
                            self->state_->count(&WebServer::Stats::timed_out);
                          }
                          self->stream_.close();
                          return;
                        }
                        if (!res->keep_alive() || self->state_->stopping) {
                          beast::error_code ignored;
                          self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                          self->stream_.close();
                          return;
                        }
                        self->readHead(self->state_->options.config.idle_timeout_s);
                      });
  }

  std::shared_ptr<Admission> admission_;
  std::shared_ptr<State> state_;
  beast::tcp_stream stream_;
  beast::tcp_stream::executor_type executor_;  // its strand (kept: stream_ may be moved away)
  std::uint64_t id_;
  bool upgraded_ = false;
  std::size_t route_class_ = kOtherRoute;
  beast::flat_buffer buffer_;
  std::optional<HeadParser> parser_;
  bool keep_alive_ = false;
  std::shared_ptr<const void> keep_;
};

}  // namespace

void State::accept() {
  acceptor.async_accept(
      asio::make_strand(io),
      asio::bind_executor(
          accept_strand, [self = shared_from_this()](beast::error_code ec, tcp::socket socket) {
            if (self->stopping) return;
            if (ec) {
              if (ec == asio::error::operation_aborted) return;
              spdlog::warn("web: accept failed: {}; retrying in 100 ms", ec.message());
              self->accept_timer.expires_after(std::chrono::milliseconds(100));
              self->accept_timer.async_wait([self](beast::error_code wait_ec) {
                if (!wait_ec && !self->stopping) self->accept();
              });
              return;
            }
            guarded("accept", [&] {
              beast::error_code peer_ec;
              const auto peer = socket.remote_endpoint(peer_ec);
              const std::string address = peer_ec ? std::string("?") : peer.address().to_string();
              std::string_view refused;
              {
                std::lock_guard lock(self->mutex);
                refused = self->limits.admit(address, self->now());
                if (!refused.empty()) ++self->stats.refused;
              }
              if (!refused.empty()) {
                spdlog::debug("web: connection from {} refused: {}", address, refused);
                socket.close(peer_ec);
                return;
              }
              auto admission = std::make_shared<Admission>(self, address);
              std::make_shared<HttpSession>(std::move(admission), std::move(socket))->start();
            });
            self->accept();
          }));
}

// ---------------------------------------------------------------- WebServer

WebServer::WebServer(std::shared_ptr<State> state) : state_(std::move(state)) {}

WebServer::~WebServer() {
  stop();
  const Stats s = stats();
  spdlog::info(
      "web: {} requests answered ({} errors, {} rate-limited), {} connections refused, {} timed "
      "out; {} spectators ({} refused for their token), {} frames sent, {} skipped",
      s.requests, s.errors, s.rate_limited, s.refused, s.timed_out, s.spectators, s.unauthorized,
      s.frames_sent, s.frames_skipped);
}

Result<std::unique_ptr<WebServer>> WebServer::start(asio::io_context& io, ServerShell& shell,
                                                    WebServerOptions options) {
  beast::error_code ec;
  const auto address = asio::ip::make_address(options.bind_address, ec);
  if (ec) return fail("web: bind address '{}': {}", options.bind_address, ec.message());
  const int port = std::max(0, options.config.port);
  auto state = std::make_shared<State>(io, shell, std::move(options));
  const tcp::endpoint endpoint(address, static_cast<std::uint16_t>(port));
  state->acceptor.open(endpoint.protocol(), ec);
  if (!ec) state->acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) state->acceptor.bind(endpoint, ec);
  if (!ec) state->acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    return fail("web: cannot listen on TCP {}:{}: {}", state->options.bind_address, port,
                ec.message());
  }
  asio::post(state->accept_strand, [state] { state->accept(); });
  return std::unique_ptr<WebServer>(new WebServer(std::move(state)));
}

std::string WebServer::localAddress() const {
  beast::error_code ec;
  const auto endpoint = state_->acceptor.local_endpoint(ec);
  return fmt::format("{}:{}", state_->options.bind_address, ec ? 0 : endpoint.port());
}

WebServer::Stats WebServer::stats() const {
  std::lock_guard lock(state_->mutex);
  return state_->stats;
}

std::vector<MetricFamily> WebServer::metricFamilies() const {
  Stats s;
  std::map<std::string, std::uint64_t, std::less<>> refusals;
  int open = 0;
  {
    std::lock_guard lock(state_->mutex);
    s = state_->stats;
    refusals = state_->limits.refusals();
    open = state_->limits.open();
  }
  for (const auto& [reason, n] : s.refusals) refusals[reason] += n;
  // Every reason is there from the start (at 0), so that rates over them are defined.
  for (const char* reason :
       {"connection limit", "connections per address", "request rate", "token", "bad request",
        "spectators per room", "bad message", "members off", "visible spectators", "host"}) {
    refusals.try_emplace(reason, 0);
  }
  std::vector<MetricFamily> out;
  auto family = [&](std::string name, std::string help, MetricType type) -> MetricFamily& {
    MetricFamily& f = out.emplace_back();
    f.name = std::move(name);
    f.help = std::move(help);
    f.type = type;
    return f;
  };
  auto value = [](std::uint64_t v) { return static_cast<double>(v); };
  MetricFamily& requests =
      family("vistel_web_requests_total",
             "Spectator web server answers by route class and status class", MetricType::kCounter);
  for (std::size_t r = 0; r < kRouteClasses.size(); ++r) {
    for (std::size_t c = 0; c < s.answers[r].size(); ++c) {
      if (s.answers[r][c] == 0) continue;
      requests.samples.push_back(
          {{{"route", kRouteClasses[r]}, {"status", fmt::format("{}xx", c + 1)}},
           value(s.answers[r][c]),
           {}});
    }
  }
  family("vistel_web_spectators", "WebSockets watching a room now", MetricType::kGauge)
      .samples.push_back({{}, value(s.spectators_open), {}});
  family("vistel_web_connections", "Spectator web server connections open (HTTP and WebSocket)",
         MetricType::kGauge)
      .samples.push_back({{}, static_cast<double>(open), {}});
  MetricFamily& bytes = family("vistel_web_sent_bytes_total",
                               "Bytes sent by the spectator web server", MetricType::kCounter);
  bytes.samples.push_back({{{"transport", "http"}}, value(s.http_bytes_sent), {}});
  bytes.samples.push_back({{{"transport", "websocket"}}, value(s.ws_bytes_sent), {}});
  MetricFamily& refused =
      family("vistel_web_refused_total",
             "Spectator web connections, requests and WebSockets refused", MetricType::kCounter);
  for (const auto& [reason, n] : refusals)
    refused.samples.push_back({{{"reason", reason}}, value(n), {}});
  family("vistel_web_timeouts_total", "Web connections closed by a read or write deadline",
         MetricType::kCounter)
      .samples.push_back({{}, value(s.timed_out), {}});
  family("vistel_web_frames_sent_total", "Binary posture frames written to spectators",
         MetricType::kCounter)
      .samples.push_back({{}, value(s.frames_sent), {}});
  family("vistel_web_frames_skipped_total",
         "Posture frames a slow spectator skipped (a newer one replaced them)",
         MetricType::kCounter)
      .samples.push_back({{}, value(s.frames_skipped), {}});
  return out;
}

void WebServer::stop() {
  if (state_->stopping.exchange(true)) return;
  asio::post(state_->accept_strand, [state = state_] {
    beast::error_code ignored;
    state->acceptor.close(ignored);
    state->accept_timer.cancel();
  });
  std::vector<std::shared_ptr<Closable>> open;
  std::vector<std::shared_ptr<RoomFeed>> feeds;
  {
    std::lock_guard lock(state_->mutex);
    for (auto& [id, weak] : state_->open) {
      if (auto c = weak.lock()) open.push_back(std::move(c));
    }
    for (auto& [room, feed] : state_->feeds) feeds.push_back(feed);
    state_->feeds.clear();
  }
  for (auto& feed : feeds) feed->stop();
  for (auto& c : open) c->close();
}

}  // namespace vistel::server
