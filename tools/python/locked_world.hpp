// One World, one call at a time: limber.World's C++ value is a LockedWorld, a World and its lock,
// and every World method and property is bound through WorldMethods, which takes that lock for
// the call. Calls from two Python threads on one World therefore serialize: 2 threads × 400
// step() calls are 800 steps, bit for bit those of one thread making them; add_body on one thread
// while another steps comes between two steps, never inside one.
//
// The GIL and the lock. step() and run() release the GIL while they hold the lock, so:
//   - a call waiting for the lock waits with the GIL released (try first, then release, lock,
//     and take the GIL back), so the holder can always get the GIL back to finish;
//   - a holder that has released the GIL takes it again only to finish (reading the result, a
//     signal check in run()), never to wait for anything else.
// A call made on the thread that already holds the World's lock (a __del__, a signal handler or
// a NumPy subclass's method run while a call converts its arguments or results) would wait for
// itself: it raises WorldError naming both calls instead.
//
// An object made by World.__new__ (or Ball.__new__, Pin.__new__) without __init__ has no value:
// pybind11 would hand the bound call uninitialised memory. The casters below refuse it first with
// a TypeError, for World and the handle classes alike.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>

#include <pybind11/pybind11.h>

#include "limber/kernel/world/world.hpp"

namespace limber::python {

namespace py = pybind11;

/// limber.World's value: the World, the name of the method it was made with (limber run's
/// --method: "weighted", "springs-implicit", ...) and the lock a bound call holds (WorldCall).
class LockedWorld {
 public:
  LockedWorld(World world, std::string method) : world_(std::move(world)), method_(std::move(method)) {}
  const std::string& method() const { return method_; }

 private:
  friend class WorldCall;
  World world_;
  const std::string method_;
  std::mutex mutex_;
  std::atomic<std::thread::id> holder_{};  // the thread inside a call (none: id()), for the re-entry check
  const char* call_ = "";                  // that call's name; written and read under mutex_
};

/// The lock of one bound call named `call` ("step"), for its lifetime: waits with the GIL released
/// when another thread holds it; throws WorldError when this thread does (a re-entry).
class WorldCall {
 public:
  WorldCall(LockedWorld& locked, const char* call) : locked_(locked) {
    if (locked.holder_.load(std::memory_order_relaxed) == std::this_thread::get_id()) {
      throw WorldError(std::string("World.") + call + ": called while World." + locked.call_ +
                       " runs on this thread (from a __del__, a signal handler or a callback); a World takes one call at a time");
    }
    if (!locked.mutex_.try_lock()) {
      py::gil_scoped_release release;  // the holder may need the GIL to finish
      locked.mutex_.lock();
    }
    locked.holder_.store(std::this_thread::get_id(), std::memory_order_relaxed);
    locked.call_ = call;
  }
  ~WorldCall() {
    locked_.holder_.store(std::thread::id(), std::memory_order_relaxed);
    locked_.mutex_.unlock();
  }
  WorldCall(const WorldCall&) = delete;
  WorldCall& operator=(const WorldCall&) = delete;
  World& world() const { return locked_.world_; }

 private:
  LockedWorld& locked_;
};

namespace detail {

// f(World&, A...) as the call a Python method makes: (LockedWorld& self, A...), under the lock.
// The result is a value (a reference's copy), made before the lock is let go. A kernel
// std::invalid_argument (an argument a method's own check refused: a vector of the wrong size)
// is a WorldError naming the call, as the World's own refusals are.
template <typename R, typename... A>
struct Locked {
  template <typename F>
  static auto wrap(const char* call, F f) {
    return [call, f = std::move(f)](LockedWorld& self, A... arguments) -> std::remove_cvref_t<R> {
      const WorldCall lock(self, call);
      try {
        return std::invoke(f, lock.world(), std::forward<A>(arguments)...);
      } catch (const std::invalid_argument& error) {
        throw WorldError(std::string(call) + ": " + error.what());
      }
    };
  }
};
template <typename F>
struct LockedCall : LockedCall<decltype(&F::operator())> {};                    // a lambda
template <typename C, typename R, typename W, typename... A>
struct LockedCall<R (C::*)(W, A...) const> : Locked<R, A...> {};                 // its call operator
template <typename R, typename W, typename... A>
struct LockedCall<R (*)(W, A...)> : Locked<R, A...> {};                          // a function
template <typename R, typename... A>
struct LockedCall<R (World::*)(A...)> : Locked<R, A...> {};                      // a World member
template <typename R, typename... A>
struct LockedCall<R (World::*)(A...) const> : Locked<R, A...> {};

}  // namespace detail

/// The methods and properties of limber.World, each a function of (World&, arguments...) (a
/// lambda or a World member), bound so that it runs under the World's lock: the only way the
/// binding files reach the class.
class WorldMethods {
 public:
  explicit WorldMethods(py::class_<LockedWorld>& bound) : class_(bound) {}

  template <typename F, typename... Extra>
  WorldMethods& def(const char* name, F f, const Extra&... extra) {
    class_.def(name, detail::LockedCall<F>::wrap(name, std::move(f)), extra...);
    return *this;
  }
  template <typename F, typename... Extra>
  WorldMethods& def_property_readonly(const char* name, F f, const Extra&... extra) {
    class_.def_property_readonly(name, detail::LockedCall<F>::wrap(name, std::move(f)), extra...);
    return *this;
  }

 private:
  py::class_<LockedWorld>& class_;
};

/// Whether `object`, an instance of T's Python class, was never given its value (T.__new__
/// without __init__).
template <typename T>
bool uninitialised(py::handle object) {
  if (!py::isinstance<T>(object)) return false;  // not ours: the caster refuses it as usual
  auto* instance = reinterpret_cast<py::detail::instance*>(object.ptr());
  const py::detail::value_and_holder value = instance->get_value_and_holder(py::detail::get_type_info(typeid(T)), false);
  return value.inst != nullptr && !value.holder_constructed();
}

/// pybind11's caster of a bound class T, refusing an uninitialised instance with a TypeError.
template <typename T>
struct InitialisedCaster : py::detail::type_caster_base<T> {
  bool load(py::handle source, bool convert) {
    if (uninitialised<T>(source)) {
      const std::string name = py::str(py::type::handle_of(source).attr("__name__"));
      throw py::type_error("this " + name + " was never initialised (" + name + ".__new__ without __init__): it has no value to use");
    }
    return py::detail::type_caster_base<T>::load(source, convert);
  }
};

}  // namespace limber::python

namespace pybind11::detail {
template <>
struct type_caster<limber::python::LockedWorld> : limber::python::InitialisedCaster<limber::python::LockedWorld> {};
template <>
struct type_caster<limber::BallId> : limber::python::InitialisedCaster<limber::BallId> {};
template <>
struct type_caster<limber::PinId> : limber::python::InitialisedCaster<limber::PinId> {};
}  // namespace pybind11::detail
