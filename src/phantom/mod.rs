//! The synthetic jaw: realistic IOS and CBCT meshes with known ground truth.
