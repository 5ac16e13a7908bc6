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

// The atmosphere's light (SUN_LIGHT, and SKY_LIGHT with it) never reaches
// a debug view, and the sky light comes only with the sun's: build.rs
// compiles no other combination (the `requires:` and `excludes:` lines of
// the object shaders).
