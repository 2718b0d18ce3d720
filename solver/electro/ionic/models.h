#pragma once
// Factories of the built-in cell models (used by the registry in cell_model.cc only).
#include <cstddef>
#include <memory>

#include "solver/electro/ionic/cell_model.h"

namespace systole::electro::ionic {

enum class Ttp06Cell { kEndo, kMid, kEpi };

std::unique_ptr<CellModel> make_aliev_panfilov(std::size_t nodes);
std::unique_ptr<CellModel> make_mitchell_schaeffer(std::size_t nodes);
std::unique_ptr<CellModel> make_fitzhugh_nagumo(std::size_t nodes);
std::unique_ptr<CellModel> make_fitzhugh_nagumo_atrial(std::size_t nodes);  // "fhn_atrial" (ours)
std::unique_ptr<CellModel> make_ttp06(std::size_t nodes, Ttp06Cell cell);

}  // namespace systole::electro::ionic
