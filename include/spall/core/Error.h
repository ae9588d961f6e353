// Typed errors: the library throws, only tools/ turns them into exit codes.
#pragma once

#include <stdexcept>
#include <string>

namespace spall {

/// What every error spall throws derives from: catch this to catch them all.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Bad user input (file, field or value); the message names the file, the field and the reason.
class InputError : public Error {
public:
    using Error::Error;
};

/// Reading or writing files failed.
class IoError : public Error {
public:
    using Error::Error;
};

/// The simulation reached a state no physics allows (a non-finite motion); the message names
/// the body and the time.
class SimulationError : public Error {
public:
    using Error::Error;
};

/// A broken invariant (SPALL_CHECK): a bug in spall, not in what it was given; the message names
/// the condition and where it was checked.
class InternalError : public Error {
public:
    using Error::Error;
};

/// Throws the InternalError of a failed SPALL_CHECK.
[[noreturn]] inline void failCheck(const char* condition, const char* file, int line)
{
    throw InternalError(std::string(file) + ":" + std::to_string(line) + ": internal check failed: " + condition +
                        " (a bug in spall; please report it with the scene)");
}

/// Cooperative cancellation and progress, shaped like OpenVDB's interrupter.
struct Interrupter {
    virtual ~Interrupter() = default;
    /// Returns true when the work should stop; `percent` is in [0, 100] or negative when unknown.
    virtual bool wasInterrupted(int percent = -1) { (void)percent; return false; }
    /// Returns true when a stop has waited longer than the step in progress should take (a
    /// step of a large lattice can take a minute): the step is given up (StepAbandoned).
    virtual bool mustAbandonStep() { return false; }
};

/// Thrown from within a simulation step that an interrupter gave up (mustAbandonStep): the state
/// is then part of a step and must not be saved; a run goes on from its last checkpoint.
class StepAbandoned : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace spall

/// An invariant the code relies on, checked in every build (pbrt-v4's CHECK): throws
/// InternalError naming the condition when it does not hold. Input is checked where it is read,
/// with InputError; this is for what no input can break.
#define SPALL_CHECK(condition) ((condition) ? static_cast<void>(0) : ::spall::failCheck(#condition, __FILE__, __LINE__))
/// The same, checked only in builds without NDEBUG (pbrt-v4's DCHECK): for checks too costly for
/// a release build's inner loops.
#ifdef NDEBUG
#define SPALL_DCHECK(condition) static_cast<void>(0)
#else
#define SPALL_DCHECK(condition) SPALL_CHECK(condition)
#endif
