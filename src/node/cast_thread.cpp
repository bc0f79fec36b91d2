#include "cast_thread.h"

#include <chrono>
#include <cmath>
#include <optional>
#include <string>

namespace laser_raycast {

CastThread::CastThread(Context context) : context_(std::move(context)) {
  takeScene();
  thread_ = std::thread([this] { run(); });
}

void CastThread::takeScene() {
  std::shared_ptr<const CastScene> scene = context_.scene->current();
  if (scene == scene_ && caster_) return;
  if (caster_) earlier_lookups_ += caster_->linkLookups();
  JobCaster::Context context;
  context.scene = &scene->scene;
  context.reflectivity = &scene->reflectivity;
  context.reflectivity_fixed = &scene->reflectivity_fixed;
  context.tf = context_.tf;
  context.sensors = context_.sensors;
  context.fixed_frame = context_.fixed_frame;
  context.tf_timeout = context_.tf_timeout;
  caster_ = std::make_unique<JobCaster>(std::move(context));
  scene_ = std::move(scene);
}

CastThread::~CastThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void CastThread::setCapacity(std::size_t capacity) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_.setCapacity(capacity);
}

void CastThread::schedule(int sensor, const std::vector<ros::Time>& times) {
  std::optional<ScanJob> dropped;
  std::size_t queued;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    dropped = queue_.push(times, sensor);
    queued = queue_.size();
  }
  wake_.notify_all();
  if (dropped) reportDropped(*dropped, queued, *context_.sensors);
}

void CastThread::run() {
  const auto poll = std::chrono::duration<double>(kPollPeriod);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    if (queue_.empty()) {
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      continue;
    }
    const ScanJob front = queue_.front();
    lock.unlock();
    takeScene();
    const ros::Time now = ros::Time::now();
    // Zero: simulated time has not started. Never before the scan's stamp: a timer that fired late
    // stamps its scan on the nearest multiple of the period, which may lie ahead, and a scan cast
    // early would miss a scene change made between its cast and its stamp.
    const bool go = !now.isZero() && now >= front.stamp() && caster_->ready(front, now);
    lock.lock();
    if (!go) {
      wake_.wait_for(lock, poll, [this] { return stop_; });
      continue;
    }
    // Sensors may have joined the job meanwhile, or an earlier job come in front of it.
    if (queue_.empty() || queue_.front().times != front.times) continue;
    const ScanJob job = queue_.pop();
    lock.unlock();
    caster_->cast(job);
    link_lookups_ = earlier_lookups_ + caster_->linkLookups();
    lock.lock();
    caster_->done(job, queue_.oldestStamp());
  }
}

std::size_t castQueueCapacity(const std::vector<std::unique_ptr<Sensor>>& sensors,
                              double tf_timeout) {
  std::size_t capacity = 0;
  for (const auto& sensor : sensors) {
    const double rate = sensor->live().rate;
    capacity += static_cast<std::size_t>(std::ceil(rate * tf_timeout)) + 2;
  }
  return capacity;
}

void reportDropped(const ScanJob& dropped, std::size_t queued,
                   const std::vector<std::unique_ptr<Sensor>>& sensors) {
  for (const int s : dropped.sensors) {
    sensors[s]->monitor().skipped(SensorMonitor::Skip::kBehind, dropped.stamp(),
                                  "the cast thread is " + std::to_string(queued) +
                                      " scans behind (casting takes longer than the scan period)");
  }
}

}  // namespace laser_raycast
