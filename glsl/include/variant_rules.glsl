// Feature combinations that reduce to simpler ones, shared by both stages
// of the object pipelines so their interfaces always match.
//
// A Gouraud surface is lit per vertex; a normal map varies within a
// triangle, so it cannot change that lighting. Outside the debug views
// (which draw the map's normals whatever the shading) the map is dropped,
// and neither stage declares the UV or tangent it would have needed.
#if defined(GOURAUD) && !defined(DEBUG_VIEW)
#undef NORMAL_MAP
#endif
