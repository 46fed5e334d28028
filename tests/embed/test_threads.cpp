// Thread safety of the C API (stex.h "Thread safety"): four threads share one context and two models and
// issue renders (host memory and cl_mem), point queries and progress-reporting renders in different orders;
// every result equals the serial result bit for bit. Also: one context per thread; analyses, saves and
// loads from four threads.
#include <CL/cl.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "embed_test_util.h"

using namespace stex_embed_test;

namespace {

struct Job {
  const stex_model* model;
  stex_render_params params;
  std::int64_t x, y;
  int width, height;
  enum Kind { Render, RenderStrided, Points, RenderProgress, RenderCl } kind;
};

int count_progress(double, void* user) {
  ++*static_cast<int*>(user);
  return 0;
}

// Runs one job on `ctx`; the result is packed (width * height * channels floats). Failures are returned as
// an empty vector plus a message (gtest assertions are not used off the main thread).
std::vector<float> run(stex_context* ctx, const Job& job, std::string* error) {
  const int nc = channels_of(job.model);
  const std::size_t row = std::size_t(job.width) * nc;
  std::vector<float> out(row * job.height);
  stex_status s = STEX_OK;
  switch (job.kind) {
    case Job::Render:
      s = stex_render(ctx, job.model, &job.params, job.x, job.y, job.width, job.height, out.data(), 0,
                      nullptr, nullptr);
      break;
    case Job::RenderStrided: {
      std::vector<float> strided((row + 3) * job.height);
      s = stex_render(ctx, job.model, &job.params, job.x, job.y, job.width, job.height, strided.data(),
                      (row + 3) * 4, nullptr, nullptr);
      for (int j = 0; j < job.height; ++j)
        std::copy(strided.begin() + std::ptrdiff_t(j * (row + 3)),
                  strided.begin() + std::ptrdiff_t(j * (row + 3) + row),
                  out.begin() + std::ptrdiff_t(j * row));
      break;
    }
    case Job::Points: {
      std::vector<double> xy;
      for (int j = 0; j < job.height; ++j)
        for (int i = 0; i < job.width; ++i) {
          xy.push_back(double(job.x + i) + 0.5);
          xy.push_back(double(job.y + j) + 0.5);
        }
      s = stex_eval_points(ctx, job.model, &job.params, xy.size() / 2, xy.data(), out.data());
      break;
    }
    case Job::RenderProgress: {
      int calls = 0;
      s = stex_render(ctx, job.model, &job.params, job.x, job.y, job.width, job.height, out.data(), 0,
                      count_progress, &calls);
      if (s == STEX_OK && calls < 2) *error = "progress was called " + std::to_string(calls) + " times";
      break;
    }
    case Job::RenderCl: {
      cl_context clctx = nullptr;
      cl_command_queue queue = nullptr;
      stex_context_cl_objects(ctx, &clctx, nullptr, &queue);
      cl_int err = CL_SUCCESS;
      cl_mem buffer = clCreateBuffer(clctx, CL_MEM_READ_WRITE, out.size() * 4, nullptr, &err);
      if (err != CL_SUCCESS) {
        *error = "clCreateBuffer failed";
        return {};
      }
      s = stex_render_cl(ctx, job.model, &job.params, job.x, job.y, job.width, job.height, buffer, 0, 0,
                         nullptr, nullptr);
      // The context's queue is shared with the other threads: reading from it is the caller's own OpenCL
      // work.
      if (s == STEX_OK && clEnqueueReadBuffer(queue, buffer, CL_TRUE, 0, out.size() * 4, out.data(), 0,
                                              nullptr, nullptr) != CL_SUCCESS)
        *error = "clEnqueueReadBuffer failed";
      clReleaseMemObject(buffer);
      break;
    }
  }
  if (s != STEX_OK) {
    *error = std::string(stex_status_name(s)) + ": " + stex_last_error();
    return {};
  }
  return out;
}

std::vector<Job> make_jobs() {
  std::vector<Job> jobs;
  const stex_model* models[] = {gravel_model(), colour_model()};
  for (int k = 0; k < 12; ++k) {
    Job j{};
    j.model = models[k % 2];
    j.params = render_params(10.0 + 5.0 * (k % 3), std::uint64_t(k / 2),
                             k % 4 == 3 ? STEX_STRATEGY_GATHER : STEX_STRATEGY_AUTO);
    j.x = std::int64_t(k) * 1000003 - 5000000;
    j.y = -std::int64_t(k) * 77;
    j.width = 40 + 8 * (k % 4);
    j.height = (k % 5 == 0) ? 64 : 24 + k;
    j.kind = static_cast<Job::Kind>(k % 5);
    if (j.params.strategy == STEX_STRATEGY_GATHER) j.width = 24;  // gather is slow on CPU devices
    jobs.push_back(j);
  }
  return jobs;
}

}  // namespace

TEST(Threads, FourThreadsOnOneContextEqualSerialOutput) {
  stex_context* ctx = context();
  const std::vector<Job> jobs = make_jobs();
  // Serial reference, all as plain renders on the same context: every kind must equal them.
  std::vector<std::vector<float>> serial;
  for (const Job& job : jobs) {
    Job plain = job;
    plain.kind = Job::Render;
    std::string error;
    serial.push_back(run(ctx, plain, &error));
    ASSERT_TRUE(error.empty()) << error;
  }
  constexpr int k_threads = 4;
  std::vector<std::vector<std::vector<float>>> results(k_threads,
                                                       std::vector<std::vector<float>>(jobs.size()));
  std::vector<std::string> errors(k_threads);
  std::atomic<int> ready{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < k_threads; ++t) {
    threads.emplace_back([&, t] {
      ++ready;
      while (ready.load() < k_threads) std::this_thread::yield();  // start together
      for (std::size_t n = 0; n < jobs.size(); ++n) {
        const std::size_t k = (n * 5 + std::size_t(t) * 3) % jobs.size();  // a different order per thread
        std::string error;
        results[t][k] = run(ctx, jobs[k], &error);
        if (!error.empty() && errors[t].empty()) errors[t] = "job " + std::to_string(k) + ": " + error;
      }
    });
  }
  for (std::thread& th : threads) th.join();
  for (int t = 0; t < k_threads; ++t) {
    EXPECT_TRUE(errors[t].empty()) << "thread " << t << ": " << errors[t];
    for (std::size_t k = 0; k < jobs.size(); ++k)
      EXPECT_EQ(bit_differences(results[t][k], serial[k]), 0u)
          << "thread " << t << " job " << k << " kind " << int(jobs[k].kind);
  }
}

TEST(Threads, OneContextPerThread) {
  const std::vector<Job> jobs = make_jobs();
  std::vector<std::vector<float>> serial;
  for (const Job& job : jobs) {
    std::string error;
    serial.push_back(run(context(), job, &error));
    ASSERT_TRUE(error.empty()) << error;
  }
  constexpr int k_threads = 2;
  std::vector<std::string> errors(k_threads);
  std::vector<std::thread> threads;
  for (int t = 0; t < k_threads; ++t) {
    threads.emplace_back([&, t] {
      stex_context* own = nullptr;
      if (stex_context_create(device_spec(), &own) != STEX_OK) {
        errors[t] = stex_last_error();
        return;
      }
      for (std::size_t k = std::size_t(t); k < jobs.size(); k += k_threads) {
        std::string error;
        const std::vector<float> got = run(own, jobs[k], &error);
        if (!error.empty() || bit_differences(got, serial[k]) != 0)
          errors[t] += "job " + std::to_string(k) + " differs " + error + "; ";
      }
      stex_context_destroy(own);
    });
  }
  for (std::thread& th : threads) th.join();
  for (int t = 0; t < k_threads; ++t) EXPECT_TRUE(errors[t].empty()) << "thread " << t << ": " << errors[t];
}

TEST(Threads, ConcurrentAnalysesEqualSerial) {
  // Analysis (host FFTs: FFTW's planner is shared) and model files from several threads at once.
  const std::vector<float> px = colour_exemplar(48, 40);
  auto analyse = [&](std::uint64_t seed, stex_model** m) {
    stex_analysis_params a;
    stex_analysis_params_init(&a, sizeof a);
    a.support = 8 + int(seed % 3);
    a.iterations = 4;
    a.seed = seed;
    return stex_model_analyse_pixels(px.data(), 48, 40, 3, 0, &a, m);
  };
  const stex_render_params p = render_params(20.0, 1);
  std::vector<std::vector<float>> serial;
  for (std::uint64_t seed = 0; seed < 4; ++seed) {
    stex_model* m = nullptr;
    ASSERT_STEX_OK(analyse(seed, &m));
    serial.push_back(render(context(), m, p, 0, 0, 24, 16));
    stex_model_destroy(m);
  }
  std::vector<stex_model*> models(4, nullptr);
  std::vector<std::string> errors(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      if (analyse(std::uint64_t(t), &models[t]) != STEX_OK) errors[t] = stex_last_error();
      const std::string path = tmp_dir() + "/thread" + std::to_string(t) + ".stex";
      stex_model* loaded = nullptr;
      if (errors[t].empty() && (stex_model_save(models[t], path.c_str()) != STEX_OK ||
                                stex_model_load(path.c_str(), &loaded) != STEX_OK))
        errors[t] = stex_last_error();
      stex_model_destroy(models[t]);
      models[t] = loaded;
    });
  for (std::thread& th : threads) th.join();
  for (int t = 0; t < 4; ++t) {
    ASSERT_TRUE(errors[t].empty()) << "thread " << t << ": " << errors[t];
    EXPECT_EQ(bit_differences(render(context(), models[t], p, 0, 0, 24, 16), serial[t]), 0u) << t;
    stex_model_destroy(models[t]);
  }
}
