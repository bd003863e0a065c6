// SPDX-License-Identifier: MIT
// pmz-encode's plan folder (--plan, --task, --assemble): an encode cut into tasks that any
// process or machine seeing the folder can run. The folder holds
//   mesh     the mesh as read (after repair), exactly: every task and the assembly start from it
//   options  the command line given to --plan (NUL-separated): its options are every step's
//   ID.region  a task's input, its cell's region (pmz::cell_regions): all a task reads of the
//            mesh (a plan without regions, made before they were, has its tasks read `mesh`)
//   tasks    the task ids, one a line: 0 to N-1, one per cell of the first cell level
//   ID.cell  a task's result (pmz::simplify_cell), written whole or not at all
// and is written in that order, `tasks` last: a runner never sees tasks without their inputs.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz::tool {

// The mesh exactly (positions, faces and every attribute, float bits kept) as bytes and back;
// false with `error` ("not a mesh plan file", "cut short") on bytes that are not one.
void mesh_to_bytes(const IndexedMesh& mesh, std::vector<uint8_t>& out);
bool mesh_from_bytes(const std::vector<uint8_t>& bytes, IndexedMesh& mesh, std::string& error);

struct EncodePlan {
  std::string dir;

  std::string file(const std::string& name) const;  // dir/name
  std::string result(const std::string& id) const { return file(id + ".cell"); }
  std::string region(const std::string& id) const { return file(id + ".region"); }
  // Whether the folder holds a plan (its `tasks`): a new plan is refused there.
  bool exists() const;

  // Writes mesh, options and the ids of `tasks` tasks. Refuses a folder that holds a plan
  // already (its results would not be this plan's). Errors name the file.
  bool write(const IndexedMesh& mesh, const std::vector<std::string>& args, uint32_t tasks,
             std::string& error) const;
  bool read_mesh(IndexedMesh& mesh, std::string& error) const;
  bool read_options(std::vector<std::string>& args, std::string& error) const;
  bool read_tasks(std::vector<std::string>& ids, std::string& error) const;
};

}  // namespace pmz::tool
