"""hearsee.audio"""
