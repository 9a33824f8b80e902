// The control channel over TLS with the real programs: a server with --tls-cert/--tls-key
// (a self-signed certificate made here with OpenSSL's API, in the scratch folder) admits
// bots that pin its certificate or trust it as their CA; a bot pinned to another
// certificate is refused saying the pin does not match; a plain bot against the TLS server
// and a TLS bot against a plain server end with a clear message, not a hang.
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "common/tls/tls_context.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/session_scratch.hpp"

namespace vistel {
namespace {

using Child = test::Program;

// A self-signed P-256 certificate for localhost and 127.0.0.1, valid for an hour, written
// as PEM to dir/name.pem and its key to dir/name.key.
bool makeCertificate(const std::string& dir, const std::string& name, long serial) {
  EVP_PKEY* key = EVP_EC_gen("P-256");
  X509* cert = X509_new();
  if (key == nullptr || cert == nullptr) return false;
  X509_set_version(cert, 2);
  ASN1_INTEGER_set(X509_get_serialNumber(cert), serial);
  X509_gmtime_adj(X509_getm_notBefore(cert), -60);
  X509_gmtime_adj(X509_getm_notAfter(cert), 3600);
  X509_set_pubkey(cert, key);
  X509_NAME* subject = X509_get_subject_name(cert);
  X509_NAME_add_entry_by_txt(subject, "CN", MBSTRING_ASC,
                             reinterpret_cast<const unsigned char*>("localhost"), -1, -1, 0);
  X509_set_issuer_name(cert, subject);
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, cert, cert, nullptr, nullptr, 0);
  bool ok = true;
  for (const auto& [nid, value] : {std::pair{NID_subject_alt_name, "DNS:localhost,IP:127.0.0.1"},
                                   std::pair{NID_basic_constraints, "critical,CA:TRUE"}}) {
    X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &ctx, nid, value);
    ok = ok && ext != nullptr && X509_add_ext(cert, ext, -1) == 1;
    X509_EXTENSION_free(ext);
  }
  ok = ok && X509_sign(cert, key, EVP_sha256()) > 0;
  FILE* cf = std::fopen((dir + "/" + name + ".pem").c_str(), "wb");
  FILE* kf = std::fopen((dir + "/" + name + ".key").c_str(), "wb");
  ok = ok && cf != nullptr && kf != nullptr && PEM_write_X509(cf, cert) == 1 &&
       PEM_write_PrivateKey(kf, key, nullptr, nullptr, 0, nullptr, nullptr) == 1;
  if (cf != nullptr) std::fclose(cf);
  if (kf != nullptr) std::fclose(kf);
  X509_free(cert);
  EVP_PKEY_free(key);
  return ok;
}

class TlsCli : public test::SessionScratch {
 protected:
  void SetUp() override {
    test::SessionScratch::SetUp();
    ASSERT_TRUE(makeCertificate(dir_, "server", 1));
    ASSERT_TRUE(makeCertificate(dir_, "other", 2));
  }

  std::vector<std::string> botArgs(const std::string& address, const std::string& name) {
    return {"--server", address,   "--room",   "lab",        "--name",     name,
            "--bvh",    bvh_path_, "--avatar", avatar_path_, "--duration", "1.5"};
  }
};

TEST_F(TlsCli, PinnedOrCaTrustingBotsJoinAndOthersAreToldWhy) {
  Child server(
      "vistel-server",
      {"--port", "0", "--tls-cert", dir_ + "/server.pem", "--tls-key", dir_ + "/server.key"},
      dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  const auto pin = tls::certificateFingerprint(dir_ + "/server.pem");
  const auto other_pin = tls::certificateFingerprint(dir_ + "/other.pem");
  ASSERT_TRUE(pin.ok() && other_pin.ok());
  ASSERT_EQ(pin->size(), 64u);

  // Pinned to the server's certificate, and trusting it as a CA: both join.
  auto pinned_args = botArgs(address, "pinned");
  pinned_args.insert(pinned_args.end(), {"--tls", "--tls-pin", *pin});
  Child pinned("vistel-bot", pinned_args, dir_ + "/pinned.log");
  auto ca_args = botArgs(address, "ca");
  ca_args.insert(ca_args.end(), {"--tls", "--tls-ca", dir_ + "/server.pem"});
  Child ca("vistel-bot", ca_args, dir_ + "/ca.log");
  EXPECT_EQ(pinned.wait(60.0), 0) << pinned.log();
  EXPECT_NE(pinned.log().find("UDP handshake done"), std::string::npos) << pinned.log();
  EXPECT_EQ(ca.wait(60.0), 0) << ca.log();
  EXPECT_NE(ca.log().find("UDP handshake done"), std::string::npos) << ca.log();

  // Pinned to another certificate: refused, saying so.
  auto wrong_args = botArgs(address, "wrong");
  wrong_args.insert(wrong_args.end(), {"--tls", "--tls-pin", *other_pin});
  Child wrong("vistel-bot", wrong_args, dir_ + "/wrong.log");
  EXPECT_EQ(wrong.wait(60.0), 1) << wrong.log();
  EXPECT_NE(wrong.log().find("TLS handshake with"), std::string::npos) << wrong.log();
  EXPECT_NE(wrong.log().find("not the pinned " + *other_pin), std::string::npos) << wrong.log();

  // A plain bot: the server drops it without an answer; the bot says what may be wrong.
  Child plain("vistel-bot", botArgs(address, "plain"), dir_ + "/plain.log");
  EXPECT_EQ(plain.wait(60.0), 1) << plain.log();
  EXPECT_NE(plain.log().find("a TLS server? try --tls"), std::string::npos) << plain.log();
  EXPECT_TRUE(server.waitForLog("TLS handshake failed", 10.0)) << server.log();
}

TEST_F(TlsCli, ATlsBotAgainstAPlainServerFailsClearly) {
  Child server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  auto args = botArgs(address, "tls");
  args.insert(args.end(), {"--tls", "--tls-ca", dir_ + "/server.pem"});
  Child bot("vistel-bot", args, dir_ + "/bot.log");
  EXPECT_EQ(bot.wait(60.0), 1) << bot.log();
  EXPECT_NE(bot.log().find("TLS handshake with"), std::string::npos) << bot.log();
  // Bad usage: a pin of the wrong form; --tls-pin without --tls.
  auto bad_pin = botArgs(address, "x");
  bad_pin.insert(bad_pin.end(), {"--tls", "--tls-pin", "abc"});
  Child bad("vistel-bot", bad_pin, dir_ + "/bad.log");
  EXPECT_EQ(bad.wait(20.0), 2) << bad.log();
  EXPECT_NE(bad.log().find("--tls-pin 'abc'"), std::string::npos) << bad.log();
  auto no_tls = botArgs(address, "y");
  no_tls.insert(no_tls.end(), {"--tls-pin", "abc"});
  Child lone("vistel-bot", no_tls, dir_ + "/lone.log");
  EXPECT_EQ(lone.wait(20.0), 2) << lone.log();
}

TEST_F(TlsCli, TheServerRefusesAKeyThatIsNotTheCertificates) {
  Child server(
      "vistel-server",
      {"--port", "0", "--tls-cert", dir_ + "/server.pem", "--tls-key", dir_ + "/other.key"},
      dir_ + "/server.log");
  EXPECT_EQ(server.wait(20.0), 1) << server.log();
  EXPECT_NE(server.log().find("--tls-key " + dir_ + "/other.key"), std::string::npos)
      << server.log();
  EXPECT_NE(server.log().find("is it the key of " + dir_ + "/server.pem?"), std::string::npos)
      << server.log();
}

}  // namespace
}  // namespace vistel
