// parallel_for over a pool of threads kept for the process: a frame of a small scene calls
// it several times (a rod step: its levels, keys, air and kernel passes; a read), and
// starting and joining a thread costs 40-60 us on this project's 2-core machine, more
// than one character's whole step (docs/performance.md, "One character, and other small
// scenes"). A job wakes only the workers it has ranges for; at exit the workers are
// stopped (not the one calling exit(), which cannot join itself) and the pool is not
// freed, since another thread may still be inside it.
//
// The ranges are the same as before (fixed by n and the thread count), so results do not
// depend on which thread runs which range. The caller runs range 0 and then takes any
// range no worker has started, so a tiny job does not wait for a worker to wake.
//
// Where the pool cannot serve a call, parallel_for starts threads for it as it did before
// the pool: a call from inside a range (nested), a call while another thread's call holds
// the pool (two simulations on two application threads), and calls after the pool's
// shutdown at exit. In a child process after fork() the parent's workers do not exist:
// the child starts a pool of its own (pthread_atfork), leaving the parent's untouched.
#include "core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#if defined(__linux__)
#include <pthread.h>
#endif

namespace kodawari {

namespace {

// True on a pool worker, and on a caller while it runs its ranges: parallel_for from
// there starts threads (the pool is busy with the outer call).
thread_local bool t_in_pool = false;

// Spins a while (a pause instruction at a time) until done() or `kSpin` have passed:
// the passes of a frame come tens of microseconds apart, and a thread that slept takes
// longer than that to wake (a futex's wake-up on this project's VM: 10-50 us), so workers
// and the waiting caller spin this long before they sleep. 150 us covers the serial part
// between a flocking substep's passes at 10 000 birds (its grid's counting sort, 60-70 us:
// at 50 us the worker slept through it and woke late for the next pass, 1.04x slower,
// docs/performance.md); where a frame's passes are further apart, the pool sleeps as
// before. Returns done().
constexpr std::chrono::microseconds kSpin{150};

template <typename Done>
bool spin_until(Done&& done) {
    const auto until = std::chrono::steady_clock::now() + kSpin;
    for (;;) {
        for (int i = 0; i < 16; ++i) {
            if (done()) return true;
#if defined(__x86_64__) || defined(__i386__)
            __builtin_ia32_pause();
#endif
        }
        if (std::chrono::steady_clock::now() >= until) return done();
    }
}

// One call's ranges: range p is fn(n p / parts, n (p + 1) / parts).
struct Job {
    const std::function<void(std::size_t, std::size_t)>* fn;
    std::size_t n, parts;
    void range(std::size_t p) const { (*fn)(n * p / parts, n * (p + 1) / parts); }
};

class Pool {
public:
    Pool() = default;
    Pool(const Pool&) = delete;
    Pool& operator=(const Pool&) = delete;
    ~Pool() { stop(); }

    // Ends the workers (a call in flight on another thread still ends: its caller runs the
    // ranges no worker took). Not the calling thread's own: exit() from inside a range.
    void stop() {
        {
            const std::lock_guard lock(m_);
            if (stop_.exchange(true)) return;
        }
        for (auto& w : workers_) w->wake.notify_one();
        for (auto& w : workers_) {
            if (w->thread.get_id() == std::this_thread::get_id()) {
                w->thread.detach();
            } else if (w->thread.joinable()) {
                w->thread.join();
            }
        }
    }

    // Runs job's every range and waits; false (nothing run) when another thread's call
    // holds the pool.
    bool try_run(const Job& job) {
        const std::size_t parts = job.parts;
        std::unique_lock submit(submit_, std::try_to_lock);
        if (!submit.owns_lock()) return false;
        std::unique_lock lock(m_);
        while (!stop_.load() && workers_.size() + 1 < parts) {
            const std::size_t index = workers_.size();
            workers_.push_back(std::make_unique<Worker>());
            workers_.back()->thread = std::thread([this, index] { work(index); });
        }
        job_ = &job;
        parts_ = parts;
        wanted_.store(parts - 1);
        next_ = 1;  // range 0 is the caller's
        finished_.store(0);
        error_ = nullptr;
        generation_.fetch_add(1);  // what spinning workers watch
        const bool sleeping = sleepers_ > 0;
        lock.unlock();
        // Only the workers this job asks for (the others sleep on: a big job once must not
        // make every later call wake them all).
        if (sleeping) {
            for (std::size_t w = 0; w + 1 < parts && w < workers_.size(); ++w) workers_[w]->wake.notify_one();
        }
        t_in_pool = true;
        run(0);
        lock.lock();
        // Ranges no worker has taken yet: the caller's, rather than waiting for a wake.
        while (next_ < parts_) {
            const std::size_t p = next_++;
            lock.unlock();
            run(p);
            lock.lock();
        }
        lock.unlock();
        if (!spin_until([this] { return finished_.load() == parts_; })) {
            lock.lock();
            done_.wait(lock, [this] { return finished_.load() == parts_; });
            lock.unlock();
        }
        t_in_pool = false;
        lock.lock();
        job_ = nullptr;
        const std::exception_ptr error = std::move(error_);
        lock.unlock();
        if (error) std::rethrow_exception(error);
        return true;
    }

private:
    // One range, its exception kept for the caller (the first one thrown).
    void run(std::size_t p) {
        std::exception_ptr error;
        try {
            job_->range(p);
        } catch (...) {
            error = std::current_exception();
        }
        const std::lock_guard lock(m_);
        if (error && !error_) error_ = std::move(error);
        error = nullptr;  // released here, under m_, not after it
        if (finished_.fetch_add(1) + 1 == parts_) done_.notify_all();
    }

    void work(std::size_t index) {
#if defined(__linux__)
        // Named for profilers and debuggers (15 characters at most).
        const std::string name = "kodawari-" + std::to_string(index + 1);
        pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
#else
        (void)index;
#endif
        t_in_pool = true;
        std::uint64_t seen = 0;  // the last job's generation this worker looked at
        // A job with fewer ranges than there are workers leaves the others asleep.
        const auto has_work = [&] { return stop_.load() || (generation_.load() != seen && index < wanted_.load()); };
        for (;;) {
            spin_until(has_work);
            std::unique_lock lock(m_);
            ++sleepers_;
            workers_[index]->wake.wait(lock, has_work);
            --sleepers_;
            if (stop_.load()) return;
            seen = generation_.load();
            // Its ranges no one has taken (none, where the caller and the others were quicker).
            while (job_ != nullptr && next_ < parts_) {
                const std::size_t p = next_++;
                lock.unlock();
                run(p);
                lock.lock();
            }
        }
    }

    std::mutex submit_;  // held by the one call the pool serves
    std::mutex m_;       // guards everything below but the atomics' reads
    struct Worker {
        std::thread thread;
        std::condition_variable wake;  // notified for the jobs that ask for this worker
    };
    std::condition_variable done_;
    std::vector<std::unique_ptr<Worker>> workers_;
    const Job* job_ = nullptr;
    std::size_t parts_ = 0, next_ = 0;
    std::atomic<std::size_t> finished_{0};
    std::atomic<std::uint64_t> generation_{0};  // one more each job
    std::atomic<std::size_t> wanted_{0};         // workers the job asks for (parts - 1)
    std::size_t sleepers_ = 0;                  // workers waiting on their Worker::wake
    std::exception_ptr error_;
    std::atomic<bool> stop_{false};
};

// The process' pool, made on first use. In a child after fork() the pointer is dropped
// (the parent's workers are not there; its pool's memory is left as it is).
std::atomic<Pool*> g_pool{nullptr};
std::atomic<bool> g_shut{false};

void forget_pool_in_child() { g_pool.store(nullptr); }

// Joins the workers at exit (or when the library is unloaded); later calls start threads.
struct PoolOwner {
    ~PoolOwner() {
        g_shut.store(true);
        if (Pool* p = g_pool.load()) p->stop();  // not freed: another thread may be inside
    }
};

Pool* pool() {
    if (g_shut.load()) return nullptr;
    Pool* p = g_pool.load();
    if (p != nullptr) return p;
    static PoolOwner owner;
#if defined(__linux__)
    static const bool registered = [] { return pthread_atfork(nullptr, nullptr, forget_pool_in_child) == 0; }();
    (void)registered;
#endif
    auto* made = new Pool();
    Pool* expected = nullptr;
    if (!g_pool.compare_exchange_strong(expected, made)) {
        delete made;  // another thread's came first
        return expected;
    }
    return made;
}

}  // namespace

unsigned resolve_threads(unsigned requested) {
    if (requested > 0) return requested;
    return std::max(1u, std::thread::hardware_concurrency());
}

void parallel_for(std::size_t n, unsigned threads, const std::function<void(std::size_t, std::size_t)>& fn) {
    const std::size_t parts = std::min<std::size_t>(std::max(1u, threads), std::max<std::size_t>(n, 1));
    if (parts <= 1) {
        fn(0, n);
        return;
    }
    const Job job{&fn, n, parts};
    if (!t_in_pool) {
        if (Pool* p = pool(); p != nullptr && p->try_run(job)) return;
    }
    // Threads of its own, each range's exception kept for the caller as the pool does.
    std::mutex m;
    std::exception_ptr error;
    const auto guarded = [&](std::size_t p) {
        try {
            job.range(p);
        } catch (...) {
            const std::lock_guard lock(m);
            if (!error) error = std::current_exception();
        }
    };
    {
        std::vector<std::jthread> workers;
        workers.reserve(parts - 1);
        for (std::size_t p = 1; p < parts; ++p) workers.emplace_back([&guarded, p] { guarded(p); });
        guarded(0);
    }  // joined
    if (error) std::rethrow_exception(error);
}

}  // namespace kodawari
