// A throw-away self-signed TLS certificate for the tests of the room server and the bridge:
// made at test time with OpenSSL's C API, never committed.
#pragma once

#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>

namespace cvephands_test {

// A throw-away self-signed certificate (EC P-256, CN=localhost, the given subjectAltName; like
// `openssl req -x509` makes one) and its key, PEM files in a fresh directory that goes with it.
struct TestCertificate {
  using path = std::filesystem::path;
  path dir, cert, key;

  explicit TestCertificate(const std::string& subject_alt_name = "IP:127.0.0.1,DNS:localhost") {
    static int serial = 0;
    dir = std::filesystem::temp_directory_path() /
          ("room_tls_" + std::to_string(::getpid()) + "_" + std::to_string(++serial));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    cert = dir / "cert.pem";
    key = dir / "key.pem";
    EVP_PKEY* pkey = EVP_EC_gen("P-256");
    X509* x = X509_new();
    if (!pkey || !x) throw std::runtime_error("TestCertificate: OpenSSL allocation");
    X509_set_version(x, 2);  // v3
    ASN1_INTEGER_set(X509_get_serialNumber(x), serial);
    X509_gmtime_adj(X509_getm_notBefore(x), -60);
    X509_gmtime_adj(X509_getm_notAfter(x), 24 * 3600);
    X509_set_pubkey(x, pkey);
    X509_NAME* name = X509_get_subject_name(x);
    X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC,
                               reinterpret_cast<const unsigned char*>("localhost"), -1, -1, 0);
    X509_set_issuer_name(x, name);  // self-signed: its own CA
    X509V3_CTX ctx;
    X509V3_set_ctx_nodb(&ctx);
    X509V3_set_ctx(&ctx, x, x, nullptr, nullptr, 0);
    const std::pair<int, std::string> extensions[] = {{NID_basic_constraints, "critical,CA:TRUE"},
                                                      {NID_subject_alt_name, subject_alt_name}};
    for (const auto& [nid, value] : extensions) {
      X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &ctx, nid, value.c_str());
      if (!ext || X509_add_ext(x, ext, -1) != 1) throw std::runtime_error("TestCertificate: extension " + value);
      X509_EXTENSION_free(ext);
    }
    if (X509_sign(x, pkey, EVP_sha256()) <= 0) throw std::runtime_error("TestCertificate: sign");
    FILE* f = std::fopen(cert.c_str(), "w");
    const bool cert_ok = f && PEM_write_X509(f, x) == 1;
    if (f) std::fclose(f);
    f = std::fopen(key.c_str(), "w");
    const bool key_ok = f && PEM_write_PrivateKey(f, pkey, nullptr, nullptr, 0, nullptr, nullptr) == 1;
    if (f) std::fclose(f);
    X509_free(x);
    EVP_PKEY_free(pkey);
    if (!cert_ok || !key_ok) throw std::runtime_error("TestCertificate: cannot write " + dir.string());
  }
  ~TestCertificate() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

}  // namespace cvephands_test
