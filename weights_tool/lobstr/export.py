"""Checkpoint -> sparsebody weights JSON (kind "lobstr") with the pipeline metadata in meta:
skeleton, lower-body joints, 6D layout, feature layout, frame rate, standing heights, credit/licence.
"""
import torch

from ..format import write_weights
from ..nets import LoBSTrNet
from .features import N_FEATURES, TRACKER_ORDER
from .skeleton import LOWER
from .standard import STANDARD

CREDIT = "Bandai Namco Research Motion Dataset, Bandai Namco Research Inc., CC BY-NC 4.0"
NON_COMMERCIAL = ("Weights trained on the Bandai Namco Research Motion Dataset (CC BY-NC 4.0): "
                  "for non-commercial use only.")


def pipeline_meta(hidden, latent, training=None, trained_on_bandai=True):
    m = {
        "frame_rate": 30.0,
        "rotation": {"representation": "6d", "layout": "columns", "columns": [2, 1]},
        "skeleton": {k: STANDARD[k] for k in ("names", "parents", "offsets")},
        "lower_body_joints": LOWER,
        "tracker_order": TRACKER_ORDER,
        "features": {
            "count": N_FEATURES,
            "layout": "[v_ref(3), w_ref 6D(6), (v(3), w 6D(6)) x head, hand_l, hand_r, pelvis height(1)]",
            "velocities": "per model frame, in the current reference frame (paper Appendix 1)",
            "reference": "pelvis on the ground, Y up, Z = ground projection of the pelvis tracker's forward",
        },
        "outputs": "[48: lower_body_joints local rotations, 6D | left foot (no contact, contact) | "
                   "right foot (no contact, contact)]",
        "window_frames": 30,
        "standing_hips_height": STANDARD["standing_hips_height"],
        "standing_head_height": STANDARD["standing_head_height"],
        "toe_height": STANDARD["toe_height"],
        "hidden": hidden,
        "latent": latent,
    }
    return add_provenance(m, trained_on_bandai, training)


def add_provenance(meta, trained_on_bandai, training=None):
    """Adds the data credit and non-commercial note (weights trained on the Bandai Namco data must carry
    them) and the training record to a weights file's meta; returns meta."""
    if trained_on_bandai:
        meta["credit"] = CREDIT
        meta["license"] = "CC BY-NC 4.0"
        meta["non_commercial"] = NON_COMMERCIAL
    if training:
        meta["training"] = training
    return meta


def export(checkpoint, out, training_command=None):
    ck = torch.load(checkpoint, map_location="cpu")
    cfg = ck["config"]
    model = LoBSTrNet(hidden=cfg["hidden"], latent=cfg["latent"])
    model.load_state_dict(ck["state_dict"], strict=True)
    training = dict(cfg)
    if training_command:
        training["command"] = training_command
    write_weights(out, ck["state_dict"], "lobstr", N_FEATURES, 52,
                  meta=pipeline_meta(cfg["hidden"], cfg["latent"], training),
                  normalization={k: v for k, v in ck["normalization"].items()})
    return out
