// OpenSSL (libssl-dev, Apache-2.0) is the library Cyclone's own security plugins use to load the
// same files, so the check reads them as Cyclone will; TinyXML-2 reads the configuration, as it
// reads Velodyne's XML calibrations.
#include "dds/identity.hpp"

#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <tinyxml2.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <vector>

namespace stac::dds {
namespace {

struct BioFree {
  void operator()(BIO* b) const { BIO_free(b); }
};
struct X509Free {
  void operator()(X509* x) const { X509_free(x); }
};
struct KeyFree {
  void operator()(EVP_PKEY* k) const { EVP_PKEY_free(k); }
};

std::string trimmed(const char* text) {
  std::string s = text == nullptr ? "" : text;
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

// A BIO over a security document's URI: "file:PATH" (or file://PATH) or "data:,TEXT"; null for
// others (pkcs11:) and files that cannot be opened.
std::unique_ptr<BIO, BioFree> open_document(const std::string& uri) {
  if (uri.rfind("data:,", 0) == 0) {
    const std::string text = uri.substr(6);
    BIO* b = BIO_new(BIO_s_mem());
    if (b != nullptr) BIO_write(b, text.data(), static_cast<int>(text.size()));
    return std::unique_ptr<BIO, BioFree>(b);
  }
  if (uri.rfind("file:", 0) != 0) return nullptr;
  std::string path = uri.substr(5);
  if (path.rfind("//", 0) == 0) path = path.substr(2);
  return std::unique_ptr<BIO, BioFree>(BIO_new_file(path.c_str(), "r"));
}

int password_callback(char* buffer, int size, int /*rwflag*/, void* user) {
  const auto* password = static_cast<const std::string*>(user);
  const int n =
      static_cast<int>(std::min<std::size_t>(password->size(), static_cast<std::size_t>(size)));
  std::memcpy(buffer, password->data(), static_cast<std::size_t>(n));
  return n;
}

rt::Status check_authentication(const tinyxml2::XMLElement& auth, const std::string& source) {
  const auto text_of = [&](const char* name) {
    const tinyxml2::XMLElement* e = auth.FirstChildElement(name);
    return e == nullptr ? std::string() : trimmed(e->GetText());
  };
  const std::string cert_uri = text_of("IdentityCertificate");
  const std::string key_uri = text_of("PrivateKey");
  std::string password = text_of("Password");
  auto cert_bio = open_document(cert_uri);
  auto key_bio = open_document(key_uri);
  if (!cert_bio || !key_bio) return {};
  std::unique_ptr<X509, X509Free> cert(
      PEM_read_bio_X509(cert_bio.get(), nullptr, nullptr, nullptr));
  std::unique_ptr<EVP_PKEY, KeyFree> key(
      PEM_read_bio_PrivateKey(key_bio.get(), nullptr, password_callback, &password));
  if (!cert || !key) return {};
  if (X509_check_private_key(cert.get(), key.get()) == 1) return {};
  const auto shown = [](const std::string& uri) {
    return uri.rfind("data:,", 0) == 0 ? std::string("the data: key given inline") : uri;
  };
  return rt::make_error(
      "DDS Security in " + source + ": the private key " + shown(key_uri) +
      " is not the key of the identity certificate " + cert_uri +
      " (their public keys differ), so no peer could authenticate this participant; give the "
      "key.pem made with that cert.pem (deploy/dds-security.sh writes them side by side)");
}

void find_authentications(const tinyxml2::XMLElement& e,
                          std::vector<const tinyxml2::XMLElement*>& out) {
  for (const tinyxml2::XMLElement* c = e.FirstChildElement(); c != nullptr;
       c = c->NextSiblingElement()) {
    if (std::strcmp(c->Name(), "Authentication") == 0) out.push_back(c);
    find_authentications(*c, out);
  }
}

rt::Status check_xml(const std::string& xml, const std::string& source) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) return {};  // Cyclone's to say
  std::vector<const tinyxml2::XMLElement*> auths;
  for (const tinyxml2::XMLElement* root = doc.FirstChildElement(); root != nullptr;
       root = root->NextSiblingElement())
    find_authentications(*root, auths);
  for (const tinyxml2::XMLElement* auth : auths)
    if (auto s = check_authentication(*auth, source); !s) return s;
  return {};
}

}  // namespace

namespace {

// Calls fn(xml, source) for each Cyclone configuration of `config_uri` (as given to
// dds_create_domain; empty: the environment's CYCLONEDDS_URI) this process can read, until fn
// returns an error. What cannot be read is left to Cyclone, which says why.
rt::Status for_each_config(
    const std::string& config_uri,
    const std::function<rt::Status(const std::string&, const std::string&)>& fn) {
  std::string uri = config_uri;
  if (uri.empty()) {
    const char* env = std::getenv("CYCLONEDDS_URI");
    uri = env == nullptr ? "" : env;
  }
  const std::string trimmed_uri = trimmed(uri.c_str());
  if (trimmed_uri.empty()) return {};
  if (trimmed_uri.front() == '<') return fn(trimmed_uri, "the configuration given inline");
  // A list of files, as Cyclone takes it (comma-separated).
  std::size_t start = 0;
  while (start <= trimmed_uri.size()) {
    std::size_t end = trimmed_uri.find(',', start);
    if (end == std::string::npos) end = trimmed_uri.size();
    std::string item = trimmed(trimmed_uri.substr(start, end - start).c_str());
    start = end + 1;
    if (item.rfind("file://", 0) == 0)
      item = item.substr(7);
    else if (item.rfind("file:", 0) == 0)
      item = item.substr(5);
    if (item.empty()) continue;
    std::ifstream in(item);
    if (!in) continue;  // Cyclone says the file is missing
    const std::string xml{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (auto s = fn(xml, item); !s) return s;
  }
  return {};
}

}  // namespace

rt::Status check_identity_keys(const std::string& config_uri) {
  return for_each_config(config_uri, check_xml);
}

bool uses_security(const std::string& config_uri) {
  bool secure = false;
  (void)for_each_config(config_uri, [&](const std::string& xml, const std::string&) -> rt::Status {
    tinyxml2::XMLDocument doc;
    if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) return {};
    std::vector<const tinyxml2::XMLElement*> auths;
    for (const tinyxml2::XMLElement* root = doc.FirstChildElement(); root != nullptr;
         root = root->NextSiblingElement())
      find_authentications(*root, auths);
    secure = secure || !auths.empty();
    return {};
  });
  return secure;
}

}  // namespace stac::dds
