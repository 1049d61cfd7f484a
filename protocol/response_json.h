#pragma once
/// \file response_json.h
/// The API's answers (SPEC §3) from the values of response_values.h.

#include <nlohmann/json.hpp>

#include <vector>

#include "protocol/response_values.h"

namespace volstyle::protocol {

nlohmann::json viewToJson(const ViewInfo& v);
nlohmann::json viewsToJson(const std::vector<ViewInfo>& views);
nlohmann::json sessionToJson(const SessionInfo& s);
nlohmann::json framesToJson(const std::vector<FrameInfo>& frames);
nlohmann::json environmentMapToJson(const EnvironmentMapInfo& m);
nlohmann::json occluderMeshToJson(const OccluderMeshInfo& m);
nlohmann::json transferImageToJson(const TransferImageInfo& t);
nlohmann::json stylizerPickToJson(const StylizerPick& p);
nlohmann::json addedTfConstraintToJson(const AddedTfConstraint& a);

}  // namespace volstyle::protocol
