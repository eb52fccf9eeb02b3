//! Reading and writing range images, previews and label maps.
