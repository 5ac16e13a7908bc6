//! [`SceneError`]: everything that can go wrong loading a scene, with the file
//! and (for semantic problems) the field path, so that a message alone is
//! enough to find and fix the problem.

/// Why a scene could not be loaded.
///
/// The `Display` form always starts with the file name, e.g.
/// `scenes/x.toml: objects[2].rotate.axis: axis has zero length`.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    // The I/O error is part of the message rather than a chained source:
    // the whole story fits on one line, and a chained source would be
    // printed twice by error reporters that walk the chain.
    #[error("{file}: cannot read scene file: {reason}")]
    Io {
        /// The scene file as given.
        file: String,
        /// The underlying error.
        reason: std::io::Error,
    },
    /// The file is not valid TOML or does not match the scene schema
    /// (unknown or missing field, wrong type). The message comes from the
    /// `toml` crate and names the line, column and field.
    #[error("{file}: {message}")]
    Parse {
        /// The scene file (or name given to `Scene::from_toml`).
        file: String,
        /// The parser's message.
        message: String,
    },
    /// The file parsed but a value is not acceptable.
    #[error("{file}: {field}: {reason}")]
    Invalid {
        /// The scene file (or name given to `Scene::from_toml`).
        file: String,
        /// Path of the offending value in the file, e.g.
        /// `objects[2].shape.radius` (array indices are zero-based).
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A model given where a scene goes could not be loaded (the
    /// loader's message names the file and line).
    #[error(transparent)]
    Model(#[from] crate::mesh::obj::ObjError),
}

impl SceneError {
    /// The field path of an [`SceneError::Invalid`] error, for tests and
    /// tools that want to point at the value.
    pub fn field(&self) -> Option<&str> {
        match self {
            SceneError::Invalid { field, .. } => Some(field),
            SceneError::Io { .. } | SceneError::Parse { .. } | SceneError::Model(_) => None,
        }
    }
}
