// The job queue on PostgreSQL (job_queue.h): table volstyle_jobs (migration 2 in
// pg_file_mirror.cpp), notifications on channel volstyle_jobs as "<id>\t<what>\t<data>".
#include <spdlog/spdlog.h>

#include <condition_variable>
#include <deque>
#include <random>
#include <thread>

#include "server/store/job_queue.h"
#include "server/store/pg_connection.h"

namespace volstyle::server {
namespace {

constexpr const char* kChannel = "volstyle_jobs";
/// PostgreSQL refuses a payload of 8000 bytes or more: a larger event is sent as "state" (read
/// the record) instead.
constexpr size_t kMaxPayload = 7900;

std::string ownerToken(const std::string& replica) {
    std::random_device rd;
    char hex[9];
    std::snprintf(hex, sizeof hex, "%08x", rd());
    return replica + "/" + hex;
}

/// A notification's payload: "<id>\t<what>\t<data>" (Receiver reads it back).
std::string payload(const std::string& id, const std::string& what, const std::string& data) { return id + "\t" + what + "\t" + data; }

/// Hands the channel's notifications to the listener of the current listen() call.
class Receiver final : public pqxx::notification_receiver {
public:
    Receiver(pqxx::connection_base& c, const JobQueue::Listener*& on) : pqxx::notification_receiver(c, kChannel), m_on(on) {}
    void operator()(const std::string& payload, int) override {
        const size_t a = payload.find('\t');
        const size_t b = a == std::string::npos ? a : payload.find('\t', a + 1);
        if (b == std::string::npos || !m_on) return;
        (*m_on)(payload.substr(0, a), payload.substr(a + 1, b - a - 1), payload.substr(b + 1));
    }

private:
    const JobQueue::Listener*& m_on;
};

/// Sends events on a thread of its own: the GL thread only queues them, so a store that is slow
/// or down delays the events, not the solve. Each wake sends what is queued in one transaction.
/// Bounded: past kMaxPending the oldest are dropped (the record still says where a job is).
class EventSender {
public:
    explicit EventSender(PgConnection& db) : m_db(db), m_thread([this] { loop(); }) {}
    ~EventSender() {
        {
            std::lock_guard lock(m_mutex);
            m_stopping = true;
        }
        m_wake.notify_all();
        m_thread.join();
    }
    void push(std::string payload) {
        {
            std::lock_guard lock(m_mutex);
            if (m_pending.size() >= kMaxPending) m_pending.pop_front();
            m_pending.push_back(std::move(payload));
        }
        m_wake.notify_all();
    }
    /// Waits (at most 2 s) until what was queued so far is sent: a job's "state" then follows
    /// its events.
    void flush() {
        std::unique_lock lock(m_mutex);
        m_sent.wait_for(lock, std::chrono::seconds(2), [&] { return m_pending.empty() && !m_sending; });
    }

private:
    static constexpr size_t kMaxPending = 1024;
    void loop() {
        std::unique_lock lock(m_mutex);
        while (true) {
            m_wake.wait(lock, [&] { return m_stopping || !m_pending.empty(); });
            if (m_pending.empty()) return;  // stopping, and nothing left
            std::deque<std::string> batch;
            batch.swap(m_pending);
            m_sending = true;
            lock.unlock();
            try {
                m_db.run("publish job events", [&](pqxx::work& tx) {
                    for (const auto& p : batch) tx.exec_params("SELECT pg_notify($1, $2)", kChannel, p);
                });
            } catch (const std::exception& e) {
                spdlog::debug("job queue: {} event(s) not sent: {}", batch.size(), e.what());
            }
            lock.lock();
            m_sending = false;
            m_sent.notify_all();
        }
    }

    PgConnection& m_db;
    std::mutex m_mutex;
    std::condition_variable m_wake, m_sent;
    std::deque<std::string> m_pending;
    bool m_sending = false, m_stopping = false;
    std::thread m_thread;  ///< last: started once the rest is ready
};

class PgJobQueue final : public JobQueue {
public:
    PgJobQueue(const std::string& url, const std::string& replica, std::chrono::milliseconds lease)
        : m_url(url), m_db(url), m_owner(ownerToken(replica)), m_lease(lease) {}

    const std::string& owner() const override { return m_owner; }
    std::chrono::milliseconds lease() const override { return m_lease; }

    void add(const std::string& id, const std::string& session, const std::string& kind, const std::string& inputs,
             const std::string& state, const std::string& record) override {
        m_db.run("record job " + id, [&](pqxx::work& tx) {
            tx.exec_params("INSERT INTO volstyle_jobs (id, session, kind, inputs, state, record, owner, lease_until) "
                           "VALUES ($1, $2, $3, $4, $5, $6, $7, now() + $8 * interval '1 millisecond')",
                           id, session, kind, inputs, state, record, m_owner, leaseMs());
        });
    }

    bool write(const std::string& id, const std::string& state, const std::string& record) override {
        m_events.flush();  // the job's events reach other replicas before its new state
        bool held = false;
        m_db.run("record job " + id, [&](pqxx::work& tx) {
            // A finished job holds no lease: nobody runs it again.
            const pqxx::result r = tx.exec_params(
                "UPDATE volstyle_jobs SET state = $2, record = $3, lease_until = CASE WHEN $2 IN ('queued', 'running') "
                "THEN lease_until ELSE NULL END WHERE id = $1 AND owner = $4 RETURNING id",
                id, state, record, m_owner);
            held = !r.empty();
            if (held) notify(tx, id, "state", "");
        });
        return held;
    }

    void publish(const std::string& id, const std::string& event, const std::string& data) override {
        m_events.push(id.size() + event.size() + data.size() + 2 < kMaxPayload ? payload(id, event, data) : payload(id, "state", ""));
    }

    std::optional<std::string> record(const std::string& id) override {
        std::optional<std::string> out;
        m_db.run("read job " + id, [&](pqxx::work& tx) {
            const pqxx::result r = tx.exec_params("SELECT record FROM volstyle_jobs WHERE id = $1", id);
            if (!r.empty()) out = r[0][0].as<std::string>();
        });
        return out;
    }

    bool requestCancel(const std::string& id) override {
        bool found = false;
        m_db.run("cancel job " + id, [&](pqxx::work& tx) {
            found = !tx.exec_params("UPDATE volstyle_jobs SET cancel = true WHERE id = $1 RETURNING id", id).empty();
            if (found) notify(tx, id, "cancel", "");
        });
        return found;
    }

    void remove(const std::string& id) override {
        m_db.run("remove job " + id, [&](pqxx::work& tx) {
            // Never another replica's running job (this copy may have lost it to that replica).
            tx.exec_params("DELETE FROM volstyle_jobs WHERE id = $1 AND (owner = $2 OR state NOT IN ('queued', 'running'))", id, m_owner);
        });
    }

    void release(const std::vector<std::string>& ids) override {
        if (ids.empty()) return;
        m_db.run("hand back the job leases", [&](pqxx::work& tx) {
            tx.exec_params("UPDATE volstyle_jobs SET lease_until = now() - interval '1 second' WHERE owner = $1 AND id = ANY($2::text[]) "
                           "AND state IN ('queued', 'running')",
                           m_owner, textArray(ids));
        });
    }

    std::vector<HeldLease> renew(const std::vector<std::string>& ids) override {
        std::vector<HeldLease> held;
        if (ids.empty()) return held;
        const std::string array = textArray(ids);
        m_db.run("renew the job leases", [&](pqxx::work& tx) {
            for (const auto& row : tx.exec_params("UPDATE volstyle_jobs SET lease_until = now() + $2 * interval '1 millisecond' "
                                                  "WHERE owner = $1 AND id = ANY($3::text[]) AND state IN ('queued', 'running') "
                                                  "RETURNING id, cancel",
                                                  m_owner, leaseMs(), array))
                held.push_back({row[0].as<std::string>(), row[1].as<bool>()});
        });
        return held;
    }

    std::optional<ClaimedJob> claimLapsed() override {
        std::optional<ClaimedJob> out;
        m_db.run("claim a job", [&](pqxx::work& tx) {
            // SKIP LOCKED: a row another replica is claiming now is passed over, not waited for.
            const pqxx::result r = tx.exec(
                "SELECT id, session, kind, inputs, coalesce(owner, ''), attempts, cancel FROM volstyle_jobs "
                "WHERE state IN ('queued', 'running') AND lease_until < now() ORDER BY created LIMIT 1 FOR UPDATE SKIP LOCKED");
            if (r.empty()) return;
            ClaimedJob c{r[0][0].as<std::string>(), r[0][1].as<std::string>(), r[0][2].as<std::string>(), r[0][3].as<std::string>(),
                         r[0][4].as<std::string>(), r[0][5].as<int>() + 1, r[0][6].as<bool>()};
            tx.exec_params("UPDATE volstyle_jobs SET owner = $2, attempts = $3, lease_until = now() + $4 * interval '1 millisecond' "
                           "WHERE id = $1",
                           c.id, m_owner, c.attempt, leaseMs());
            out = std::move(c);
        });
        return out;
    }

    void listen(const Listener& on, std::chrono::milliseconds timeout) override {
        try {
            if (!m_listenConn || !m_listenConn->is_open()) {
                m_receiver.reset();
                m_listenConn = connectToStore(m_url);
                m_receiver = std::make_unique<Receiver>(*m_listenConn, m_on);
            }
            m_on = &on;
            const long us = long(std::chrono::duration_cast<std::chrono::microseconds>(timeout).count());
            m_listenConn->await_notification(us / 1000000, us % 1000000);
            m_on = nullptr;
        } catch (const std::exception& e) {
            m_on = nullptr;
            m_receiver.reset();
            m_listenConn.reset();
            spdlog::warn("job queue: listening to {} failed ({}); listening again", m_db.describe(), e.what());
            std::this_thread::sleep_for(timeout);  // a store that is down is not asked again at once
        }
    }

    std::vector<std::pair<std::string, long long>> countByState() override {
        std::vector<std::pair<std::string, long long>> out;
        m_db.run("count the jobs", [&](pqxx::work& tx) {
            for (const auto& row : tx.exec("SELECT state, count(*) FROM volstyle_jobs GROUP BY state ORDER BY state"))
                out.emplace_back(row[0].as<std::string>(), row[1].as<long long>());
        });
        return out;
    }

private:
    /// A text[] literal of job ids (hex digits: nothing to quote).
    static std::string textArray(const std::vector<std::string>& ids) {
        std::string array = "{";
        for (const auto& id : ids) array += (array.size() > 1 ? "," : "") + id;
        return array + "}";
    }
    long long leaseMs() const { return static_cast<long long>(m_lease.count()); }
    static void notify(pqxx::work& tx, const std::string& id, const std::string& what, const std::string& data) {
        tx.exec_params("SELECT pg_notify($1, $2)", kChannel, payload(id, what, data));
    }

    std::string m_url;
    PgConnection m_db;
    std::string m_owner;
    std::chrono::milliseconds m_lease;
    // The listener's own connection (listen() runs on one thread).
    std::unique_ptr<pqxx::connection> m_listenConn;
    std::unique_ptr<Receiver> m_receiver;
    const Listener* m_on = nullptr;
    EventSender m_events{m_db};  ///< last: its thread stops first
};

}  // namespace

std::unique_ptr<JobQueue> openPostgresJobQueue(const std::string& url, const std::string& replica, std::chrono::milliseconds lease) {
    return std::make_unique<PgJobQueue>(url, replica, lease);
}

}  // namespace volstyle::server
