//! Copies between attachments and host-visible buffers outside the render
//! pass: an upload copies a given HDR image into the HDR attachment before
//! it (tone-mapping an existing image), a readback copies attachments out
//! after it. What to copy comes from the pass's declaration.

use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::RenderError;
use crate::vk::{Buffer, BufferUsage, CommandBuffer};

pub struct TransferPass {
    /// (attachment, buffer) copied into the attachment.
    uploads: Vec<(&'static str, Buffer)>,
    /// (attachment, buffer) the attachment is copied into.
    readbacks: Vec<(&'static str, Buffer)>,
}

/// The upload in the frame's list ([`super::PASSES`]): in the frame that
/// tone-maps an HDR image, the image copied into the HDR attachment.
pub const HDR_UPLOAD: &dyn PassType = &Direction::Upload;
/// The readback in the frame's list: the output, and the HDR image when
/// the frame keeps it, copied out.
pub const READBACK: &dyn PassType = &Direction::Readback;

enum Direction {
    Upload,
    Readback,
}

impl PassType for Direction {
    fn name(&self) -> &'static str {
        match self {
            Direction::Upload => "hdr upload",
            Direction::Readback => "readback",
        }
    }

    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        use attachment::*;
        match self {
            Direction::Upload => shape.scene.is_none().then(|| PassIo::Transfer {
                reads: vec![],
                writes: vec![HDR],
            }),
            Direction::Readback => {
                let mut reads = vec![OUTPUT];
                if shape.keep_hdr {
                    reads.push(HDR);
                }
                Some(PassIo::Transfer {
                    reads,
                    writes: vec![],
                })
            }
        }
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }

    fn is_subpass(&self) -> bool {
        false
    }
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let PassIo::Transfer { reads, writes } = &setup.decl.io else {
        return Err(RenderError::Frame(format!(
            "pass '{}' is not a transfer",
            setup.decl.name()
        )));
    };
    let mut uploads = Vec::new();
    for &name in writes {
        let image = match (name, setup.hdr_input) {
            (attachment::HDR, Some(image)) => image,
            _ => {
                return Err(RenderError::InvalidImage(format!(
                    "nothing to upload into attachment '{name}'"
                )))
            }
        };
        let buffer = Buffer::with_data(
            setup.ctx,
            "hdr upload",
            bytemuck::cast_slice(&image.data),
            BufferUsage::Upload,
        )?;
        uploads.push((name, buffer));
    }
    let mut readbacks = Vec::new();
    for &name in reads {
        let image = setup.frame.attachments.get(name)?;
        let bytes = crate::vk::bytes_per_texel(image.desc.format)
            * u64::from(image.desc.width)
            * u64::from(image.desc.height);
        let buffer = Buffer::new(setup.ctx, name, bytes, BufferUsage::Readback)?;
        readbacks.push((name, buffer));
    }
    Ok(Box::new(TransferPass { uploads, readbacks }))
}

impl RecordPass for TransferPass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        for (name, buffer) in &self.uploads {
            cmd.copy_buffer_to_image(buffer, frame.attachments.get(name)?);
        }
        for (name, buffer) in &self.readbacks {
            cmd.copy_image_to_buffer(frame.attachments.get(name)?, buffer);
        }
        Ok(())
    }

    fn readback(&self, attachment: &str) -> Option<&Buffer> {
        self.readbacks
            .iter()
            .find(|(n, _)| *n == attachment)
            .map(|(_, b)| b)
    }
}
