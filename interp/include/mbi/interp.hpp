#pragma once
// Umbrella header of mbi::interp.
#include <mbi/interp/adjoint.hpp>
#include <mbi/interp/control.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/interp/fast_evaluate.hpp>
#include <mbi/interp/mesh.hpp>
#include <mbi/interp/metrics.hpp>
#include <mbi/interp/modified_bi.hpp>
#include <mbi/interp/outside.hpp>
#include <mbi/interp/phong.hpp>
#include <mbi/interp/threads.hpp>
