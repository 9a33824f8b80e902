// TLS contexts (common/tls/tls_context.hpp): a server context from a certificate and its
// key, the errors for missing files and a key of another certificate, client contexts
// from a pin or a CA file, and certificate fingerprints. Certificates are made here with
// OpenSSL's API in the scratch folder.
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <cctype>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "common/tls/tls_context.hpp"
#include "tests/support/test_support.hpp"

namespace vistel::tls {
namespace {

// A self-signed P-256 certificate (dir/name.pem) and its key (dir/name.key).
void makeCertificate(const std::string& dir, const std::string& name) {
  EVP_PKEY* key = EVP_EC_gen("P-256");
  X509* cert = X509_new();
  ASSERT_TRUE(key != nullptr && cert != nullptr);
  X509_set_version(cert, 2);
  ASN1_INTEGER_set(X509_get_serialNumber(cert), 7);
  X509_gmtime_adj(X509_getm_notBefore(cert), 0);
  X509_gmtime_adj(X509_getm_notAfter(cert), 3600);
  X509_set_pubkey(cert, key);
  X509_NAME_add_entry_by_txt(X509_get_subject_name(cert), "CN", MBSTRING_ASC,
                             reinterpret_cast<const unsigned char*>(name.c_str()), -1, -1, 0);
  X509_set_issuer_name(cert, X509_get_subject_name(cert));
  ASSERT_GT(X509_sign(cert, key, EVP_sha256()), 0);
  FILE* cf = std::fopen((dir + "/" + name + ".pem").c_str(), "wb");
  FILE* kf = std::fopen((dir + "/" + name + ".key").c_str(), "wb");
  ASSERT_TRUE(cf != nullptr && kf != nullptr);
  EXPECT_EQ(PEM_write_X509(cf, cert), 1);
  EXPECT_EQ(PEM_write_PrivateKey(kf, key, nullptr, nullptr, 0, nullptr, nullptr), 1);
  std::fclose(cf);
  std::fclose(kf);
  X509_free(cert);
  EVP_PKEY_free(key);
}

TEST(TlsContext, ServerContextNeedsACertificateAndItsKey) {
  const std::string dir = test::scratchDir();
  makeCertificate(dir, "a");
  makeCertificate(dir, "b");
  EXPECT_TRUE(makeServerContext(dir + "/a.pem", dir + "/a.key").ok());
  const auto missing = makeServerContext(dir + "/none.pem", dir + "/a.key");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("--tls-cert " + dir + "/none.pem"), std::string::npos)
      << missing.error().message;
  const auto other_key = makeServerContext(dir + "/a.pem", dir + "/b.key");
  ASSERT_FALSE(other_key.ok());
  EXPECT_NE(other_key.error().message.find("is it the key of"), std::string::npos)
      << other_key.error().message;
}

TEST(TlsContext, ClientContextsFromAPinOrACaFile) {
  const std::string dir = test::scratchDir();
  makeCertificate(dir, "a");
  const auto pin = certificateFingerprint(dir + "/a.pem");
  ASSERT_TRUE(pin.ok()) << pin.error().message;
  EXPECT_EQ(pin->size(), 64u);
  EXPECT_EQ(pin->find_first_not_of("0123456789abcdef"), std::string::npos) << *pin;
  ClientTlsSettings pinned{true, "", *pin};
  EXPECT_TRUE(makeClientContext(pinned).ok());
  // Upper-case hex is the same pin; anything else is refused naming it.
  std::string upper = *pin;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  EXPECT_TRUE(makeClientContext({true, "", upper}).ok());
  const auto short_pin = makeClientContext({true, "", "abcd"});
  ASSERT_FALSE(short_pin.ok());
  EXPECT_NE(short_pin.error().message.find("--tls-pin 'abcd'"), std::string::npos);
  EXPECT_TRUE(makeClientContext({true, dir + "/a.pem", ""}).ok());
  const auto no_ca = makeClientContext({true, dir + "/none.pem", ""});
  ASSERT_FALSE(no_ca.ok());
  EXPECT_NE(no_ca.error().message.find("--tls-ca"), std::string::npos);
  EXPECT_FALSE(certificateFingerprint(dir + "/none.pem").ok());
  EXPECT_FALSE(certificateFingerprint(dir + "/a.key").ok());
}

}  // namespace
}  // namespace vistel::tls
