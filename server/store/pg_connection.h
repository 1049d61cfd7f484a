#pragma once
/// \file pg_connection.h
/// One libpq connection to the store and the transaction helper the PostgreSQL parts share (the
/// file mirror, the job queue): a 5 s connect timeout, a broken connection opened again once,
/// and every failure an IoError naming the store without its password. Included only by the
/// PostgreSQL translation units (libpqxx stays out of the rest of the server).

#include <pqxx/pqxx>

#include <memory>
#include <mutex>
#include <string>

#include "core/base/errors.h"
#include "protocol/error_body.h"
#include "server/store/file_mirror.h"

namespace volstyle::server {

/// Opens `url` (a libpq connection string or postgresql:// URI) with a connect timeout; IoError.
std::unique_ptr<pqxx::connection> connectToStore(const std::string& url);

class PgConnection {
public:
    explicit PgConnection(std::string url) : m_url(std::move(url)), m_conn(connectToStore(m_url)) {}
    std::string describe() const { return withoutPassword(m_url); }

    /// One transaction on this connection (one at a time); `what` names it in errors. ApiErrors
    /// the body throws pass through as they are.
    template <typename F>
    void run(const std::string& what, F&& body) {
        std::lock_guard lock(m_mutex);
        for (int attempt = 0;; ++attempt) {
            try {
                if (!m_conn || !m_conn->is_open()) m_conn = connectToStore(m_url);
                pqxx::work tx(*m_conn);
                body(tx);
                tx.commit();
                return;
            } catch (const pqxx::broken_connection& e) {
                m_conn.reset();
                if (attempt == 0) continue;
                throw IoError("the store " + describe() + " is unreachable (" + what + "): " + e.what());
            } catch (const IoError&) {
                throw;
            } catch (const protocol::ApiError&) {
                throw;
            } catch (const std::exception& e) {
                throw IoError("the store " + describe() + " failed to " + what + ": " + e.what());
            }
        }
    }

private:
    std::string m_url;
    std::unique_ptr<pqxx::connection> m_conn;
    std::mutex m_mutex;
};

}  // namespace volstyle::server
