#include "server/store/pg_connection.h"

namespace volstyle::server {

std::unique_ptr<pqxx::connection> connectToStore(const std::string& url) {
    try {
        // A database that does not answer fails a request (and /ready) in 5 s, not never.
        const bool uri = url.rfind("postgres", 0) == 0 && url.find("://") != std::string::npos;
        const std::string withTimeout = url.find("connect_timeout") != std::string::npos ? url
                                        : uri ? url + (url.find('?') == std::string::npos ? "?" : "&") + "connect_timeout=5"
                                              : url + " connect_timeout=5";
        return std::make_unique<pqxx::connection>(withTimeout);
    } catch (const std::exception& e) {
        throw IoError("cannot connect to the store " + withoutPassword(url) + ": " + e.what());
    }
}

}  // namespace volstyle::server
