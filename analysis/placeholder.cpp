// Placeholder so that stex_analysis has a source until analysis lands; delete when another .cpp exists.
namespace stex { int analysis_placeholder = 0; }
