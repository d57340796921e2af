#pragma once
// The C++ objects that several parts of the module share: a simulator stepped from Python and
// also driving a FramePipeline, and the drivers a pipeline takes. Each is held by a shared_ptr
// so that Python keeps its handle after a pipeline takes the object in (set_targets, pokes).
#include "bindings.hpp"

#include <mbi/pipeline/driver.hpp>
#include <mbi/sim/simulator.hpp>

#include <memory>

namespace mbi::python {

using SimulatorObject = Guarded<sim::Simulator>;
using HandleDriverObject = Guarded<pipeline::HandleDriver>;
using GivenDriverObject = Guarded<pipeline::GivenDriver>;

/// sim::Parameters with the keys of `options` (the keyword arguments of Simulator and
/// set_params: dt, substeps, gravity, ...) applied to `base`; an unknown key is an Error.
sim::Parameters simulation_parameters(const py::dict& options, sim::Parameters base);

}  // namespace mbi::python
